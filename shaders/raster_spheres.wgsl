// Sphere occupancy on an integer lattice (rfta-raster, GPU path).
//
// One invocation per (sphere, x column of its candidate cells): every candidate cell's jittered
// sample point is tested against the sphere with integer arithmetic, and the bits of each 32-cell
// word are OR-ed into the grid at once. The CPU path (crates/rfta-raster/src/cpu.rs) uses the same
// hash, lattice and test, so both produce the same bits.
//
// spheres: 10 words per sphere: centre x y z (i32 bits), threshold r2, lo x y z, hi x y z.
// occ: one bit per cell; cell (ix, iy, iz) is bit iz % 32 of word (ix * res + iy) * words_per_column + iz / 32.

struct Params {
    res: u32,
    words_per_column: u32,
    seed: u32,
    n_spheres: u32,
    sphere_offset: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> spheres: array<u32>;
@group(0) @binding(2) var<storage, read_write> occ: array<atomic<u32>>;

const SUBCELLS: u32 = 16u;

// The PCG output permutation (O'Neill 2014), as lattice.rs's pcg_hash.
fn pcg_hash(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

@compute @workgroup_size(64, 1, 1)
fn raster_spheres(@builtin(global_invocation_id) gid: vec3<u32>) {
    let s = gid.x + params.sphere_offset;
    if (s >= params.n_spheres) {
        return;
    }
    let b = s * 10u;
    let c = vec3<i32>(bitcast<i32>(spheres[b]), bitcast<i32>(spheres[b + 1u]), bitcast<i32>(spheres[b + 2u]));
    let r2 = spheres[b + 3u];
    let lo = vec3<u32>(spheres[b + 4u], spheres[b + 5u], spheres[b + 6u]);
    let hi = vec3<u32>(spheres[b + 7u], spheres[b + 8u], spheres[b + 9u]);
    if (lo.x > hi.x || lo.y > hi.y || lo.z > hi.z) {
        return;
    }
    let ix = lo.x + gid.y;
    if (ix > hi.x) {
        return;
    }
    let res = params.res;
    for (var iy = lo.y; iy <= hi.y; iy = iy + 1u) {
        let column = (ix * res + iy) * params.words_per_column;
        var word = lo.z / 32u;
        var bits = 0u;
        for (var iz = lo.z; iz <= hi.z; iz = iz + 1u) {
            if (iz / 32u != word) {
                if (bits != 0u) {
                    atomicOr(&occ[column + word], bits);
                }
                bits = 0u;
                word = iz / 32u;
            }
            let cell = (ix * res + iy) * res + iz;
            let h1 = pcg_hash(cell ^ params.seed);
            let h2 = pcg_hash(h1);
            let h3 = pcg_hash(h2);
            let x = vec3<i32>(
                i32(ix * SUBCELLS + (h1 >> 28u)),
                i32(iy * SUBCELLS + (h2 >> 28u)),
                i32(iz * SUBCELLS + (h3 >> 28u)),
            );
            let d = x - c;
            // |d| <= 2^15 per axis, so each square fits i32 and the sum fits u32.
            let d2 = u32(d.x * d.x) + u32(d.y * d.y) + u32(d.z * d.z);
            if (d2 <= r2) {
                bits = bits | (1u << (iz % 32u));
            }
        }
        if (bits != 0u) {
            atomicOr(&occ[column + word], bits);
        }
    }
}
