//! Occupancy on the GPU with wgpu compute.

use std::sync::{Arc, Mutex, OnceLock};

use wgpu::util::DeviceExt;

use crate::band::BitGrid;
use crate::lattice::{QSphere, seed32};
use crate::{Error, RasterParams, shaders};

/// Words of sphere data per sphere in the GPU buffer.
const SPHERE_WORDS: usize = 10;
/// Invocations per workgroup (the shader's `workgroup_size`).
const WORKGROUP: u32 = 64;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    res: u32,
    words_per_column: u32,
    seed: u32,
    n_spheres: u32,
    sphere_offset: u32,
    n_blocks: u32,
    block_words_per_column: u32,
    pad: u32,
}

/// Cells per block side (as cpu.rs and the shader).
const BLOCK: usize = 8;

/// A wgpu device with the rasterization pipeline compiled.
#[derive(Debug)]
pub struct GpuRasterizer {
    device: wgpu::Device,
    queue: wgpu::Queue,
    /// The three passes: cover blocks, rasterize uncovered blocks, fill covered blocks.
    cover: wgpu::ComputePipeline,
    raster: wgpu::ComputePipeline,
    fill: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    adapter_info: wgpu::AdapterInfo,
    /// Errors wgpu reported asynchronously (its default handler would panic).
    errors: Arc<Mutex<Vec<String>>>,
}

impl GpuRasterizer {
    /// The process-wide rasterizer, created on first use; `None` when no adapter exists.
    /// `WGPU_BACKEND` and `WGPU_ADAPTER_NAME` select the adapter.
    pub fn shared() -> Option<&'static GpuRasterizer> {
        static SHARED: OnceLock<Option<GpuRasterizer>> = OnceLock::new();
        SHARED
            .get_or_init(|| pollster::block_on(Self::new()))
            .as_ref()
    }

    /// A new rasterizer on the default adapter; `None` when none can be opened.
    pub async fn new() -> Option<Self> {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let adapter = wgpu::util::initialize_adapter_from_env_or_default(&instance, None)
            .await
            .ok()?;
        let desc = wgpu::DeviceDescriptor {
            required_limits: adapter.limits(),
            ..Default::default()
        };
        let (device, queue) = adapter.request_device(&desc).await.ok()?;
        let errors: Arc<Mutex<Vec<String>>> = Arc::default();
        let sink = errors.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            if let Ok(mut v) = sink.lock() {
                v.push(e.to_string());
            }
        }));
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("raster_spheres.wgsl"),
            source: wgpu::ShaderSource::Wgsl(shaders::RASTER_SPHERES.into()),
        });
        let entry = |binding, ty| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("raster_spheres"),
            entries: &[
                entry(0, wgpu::BufferBindingType::Uniform),
                entry(1, wgpu::BufferBindingType::Storage { read_only: true }),
                entry(2, wgpu::BufferBindingType::Storage { read_only: false }),
                entry(3, wgpu::BufferBindingType::Storage { read_only: false }),
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("raster_spheres"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = |entry: &str| {
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry),
                layout: Some(&pipeline_layout),
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            })
        };
        let (cover, raster, fill) = (
            pipeline("cover_blocks"),
            pipeline("raster_spheres"),
            pipeline("fill_covered"),
        );
        let gpu = Self {
            device,
            queue,
            cover,
            raster,
            fill,
            layout,
            adapter_info: adapter.get_info(),
            errors,
        };
        if let Err(e) = gpu.take_errors() {
            log::warn!(
                "the GPU rasterizer could not be set up on {}: {e}",
                gpu.describe()
            );
            return None;
        }
        Some(gpu)
    }

    /// The errors wgpu reported since the last call, as one error.
    fn take_errors(&self) -> Result<(), Error> {
        let mut v = self
            .errors
            .lock()
            .map_err(|_| Error::Gpu("error log poisoned".into()))?;
        if v.is_empty() {
            Ok(())
        } else {
            Err(Error::Gpu(std::mem::take(&mut *v).join("; ")))
        }
    }

    /// The adapter's name and backend, for logs and test output.
    pub fn describe(&self) -> String {
        format!(
            "{} ({:?}, {:?})",
            self.adapter_info.name, self.adapter_info.backend, self.adapter_info.device_type
        )
    }

    /// Occupancy of the lattice spheres; `None` when the buffers exceed the device's limits.
    pub(crate) fn occupancy(
        &self,
        spheres: &[QSphere],
        params: &RasterParams,
    ) -> Result<Option<BitGrid>, Error> {
        let res = params.res;
        let words_per_column64 = res.div_ceil(64);
        let n_words64 = res * res * words_per_column64;
        let occ_bytes = (n_words64 * 8) as u64;
        let sphere_bytes = (spheres.len().max(1) * SPHERE_WORDS * 4) as u64;
        let limits = self.device.limits();
        let binding_limit = limits.max_storage_buffer_binding_size;
        if occ_bytes > binding_limit.min(limits.max_buffer_size)
            || sphere_bytes > binding_limit.min(limits.max_buffer_size)
        {
            return Ok(None);
        }
        let data = sphere_words(spheres);
        let sphere_buf = self
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("spheres"),
                contents: bytemuck::cast_slice(&data),
                usage: wgpu::BufferUsages::STORAGE,
            });
        let occ_buf = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("occupancy"),
            size: occ_bytes,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let read_buf = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("occupancy readback"),
            size: occ_bytes,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let n_blocks = res.div_ceil(BLOCK);
        let block_words = n_blocks.div_ceil(32);
        let covered_buf = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("covered blocks"),
            size: (n_blocks * n_blocks * block_words * 4).max(4) as u64,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        // The widest candidate x range in blocks sets the dispatches' second dimension.
        let live = || {
            spheres
                .iter()
                .filter(|s| s.lo.iter().zip(&s.hi).all(|(l, h)| l <= h))
        };
        let block = BLOCK as u32;
        let max_bx = live()
            .map(|s| s.hi[0] / block - s.lo[0] / block + 1)
            .max()
            .unwrap_or(0);
        let per_dispatch = limits.max_compute_workgroups_per_dimension.min(65_535) * WORKGROUP;
        let base = Params {
            res: res as u32,
            words_per_column: (2 * words_per_column64) as u32,
            seed: seed32(params.seed),
            n_spheres: spheres.len() as u32,
            sphere_offset: 0,
            n_blocks: n_blocks as u32,
            block_words_per_column: block_words as u32,
            pad: 0,
        };
        let binds = self.bind_groups(base, per_dispatch, [&sphere_buf, &occ_buf, &covered_buf]);
        // Separate passes order the phases: every cover write lands before any raster read, and
        // every raster write before the fill.
        let mut encoder = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("raster"),
            });
        let pass_desc = wgpu::ComputePassDescriptor {
            label: Some("raster"),
            timestamp_writes: None,
        };
        for (pipeline, y) in [(&self.cover, max_bx), (&self.raster, max_bx)] {
            for (bind, n) in binds.iter().filter(|_| y > 0) {
                let mut pass = encoder.begin_compute_pass(&pass_desc);
                pass.set_pipeline(pipeline);
                pass.set_bind_group(0, bind, &[]);
                pass.dispatch_workgroups(n.div_ceil(WORKGROUP), y, 1);
            }
        }
        if let Some((bind, _)) = binds.first() {
            let mut pass = encoder.begin_compute_pass(&pass_desc);
            pass.set_pipeline(&self.fill);
            pass.set_bind_group(0, bind, &[]);
            let groups = (res as u32).div_ceil(8);
            pass.dispatch_workgroups(groups, groups, 1);
        }
        self.queue.submit([encoder.finish()]);
        let words = self.read_back(&occ_buf, &read_buf)?;
        self.take_errors()?;
        Ok(Some(BitGrid::from_words(res, words)))
    }

    /// One bind group per chunk of at most `per_dispatch` spheres, with `base`'s parameters and
    /// the chunk's offset, over `buffers` (spheres, occupancy, covered blocks).
    fn bind_groups(
        &self,
        base: Params,
        per_dispatch: u32,
        buffers: [&wgpu::Buffer; 3],
    ) -> Vec<(wgpu::BindGroup, u32)> {
        fn entry(binding: u32, buffer: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
            wgpu::BindGroupEntry {
                binding,
                resource: buffer.as_entire_binding(),
            }
        }
        let [sphere_buf, occ_buf, covered_buf] = buffers;
        let mut binds = Vec::new();
        let mut offset = 0u32;
        while offset < base.n_spheres {
            let n = (base.n_spheres - offset).min(per_dispatch);
            let p = Params {
                sphere_offset: offset,
                ..base
            };
            let param_buf = self
                .device
                .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("raster params"),
                    contents: bytemuck::bytes_of(&p),
                    usage: wgpu::BufferUsages::UNIFORM,
                });
            let bind = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("raster_spheres"),
                layout: &self.layout,
                entries: &[
                    entry(0, &param_buf),
                    entry(1, sphere_buf),
                    entry(2, occ_buf),
                    entry(3, covered_buf),
                ],
            });
            binds.push((bind, n));
            offset += n;
        }
        binds
    }

    /// The words of `buf`, through `read_buf` (as large, mappable).
    fn read_back(&self, buf: &wgpu::Buffer, read_buf: &wgpu::Buffer) -> Result<Vec<u64>, Error> {
        let mut encoder = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("readback"),
            });
        encoder.copy_buffer_to_buffer(buf, 0, read_buf, 0, None);
        self.queue.submit([encoder.finish()]);
        let (tx, rx) = std::sync::mpsc::channel();
        read_buf.map_async(wgpu::MapMode::Read, .., move |r| {
            let _ = tx.send(r);
        });
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| Error::Gpu(e.to_string()))?;
        rx.recv()
            .map_err(|e| Error::Gpu(e.to_string()))?
            .map_err(|e| Error::Gpu(e.to_string()))?;
        let view = read_buf
            .get_mapped_range(..)
            .map_err(|e| Error::Gpu(format!("{e:?}")))?;
        let words: Vec<u64> = view
            .chunks_exact(8)
            .map(|c| u64::from_le_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]]))
            .collect();
        drop(view);
        read_buf.unmap();
        Ok(words)
    }
}

/// The spheres as the shader reads them, [`SPHERE_WORDS`] words each (one sphere of zeros when
/// there are none: a buffer may not be empty).
fn sphere_words(spheres: &[QSphere]) -> Vec<u32> {
    let mut data: Vec<u32> = Vec::with_capacity(spheres.len().max(1) * SPHERE_WORDS);
    for s in spheres {
        data.extend(s.c.map(|v| v as u32));
        data.push(s.r2);
        data.extend(s.lo);
        data.extend(s.hi);
    }
    if data.is_empty() {
        data.resize(SPHERE_WORDS, 0);
    }
    data
}

#[cfg(test)]
mod tests {
    use std::mem::{offset_of, size_of};

    use super::Params;

    /// The Rust `Params` and the shader's `Params` have the same size and member offsets, as naga
    /// lays the WGSL struct out.
    #[test]
    fn params_layout_matches_the_shader() {
        let module =
            naga::front::wgsl::parse_str(crate::shaders::RASTER_SPHERES).expect("valid WGSL");
        let mut layouter = naga::proc::Layouter::default();
        layouter.update(module.to_ctx()).expect("layout");
        let (handle, ty) = module
            .types
            .iter()
            .find(|(_, t)| t.name.as_deref() == Some("Params"))
            .expect("the shader declares Params");
        let naga::TypeInner::Struct { members, span } = &ty.inner else {
            panic!("Params is a struct")
        };
        assert_eq!(*span as usize, size_of::<Params>());
        assert_eq!(layouter[handle].size as usize, size_of::<Params>());
        let rust = [
            ("res", offset_of!(Params, res)),
            ("words_per_column", offset_of!(Params, words_per_column)),
            ("seed", offset_of!(Params, seed)),
            ("n_spheres", offset_of!(Params, n_spheres)),
            ("sphere_offset", offset_of!(Params, sphere_offset)),
            ("n_blocks", offset_of!(Params, n_blocks)),
            (
                "block_words_per_column",
                offset_of!(Params, block_words_per_column),
            ),
            ("pad", offset_of!(Params, pad)),
        ];
        assert_eq!(members.len(), rust.len());
        for (m, (name, offset)) in members.iter().zip(rust) {
            assert_eq!(m.name.as_deref(), Some(name));
            assert_eq!(m.offset as usize, offset, "{name}");
        }
    }
}
