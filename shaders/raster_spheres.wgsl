// Sphere occupancy on an integer lattice (rfta-raster, GPU path).
//
// Three passes, as the CPU path (cpu.rs): cover_blocks marks the 8^3-cell blocks a sphere holds
// entirely; raster_spheres rasterizes cells only in blocks no sphere covers; fill_covered sets the
// covered blocks' cells. Which blocks get marked only changes the work, never the bits.
//
// The CPU path uses the same hash, lattice and integer test, so both produce the same bits.
//
// spheres: 10 words per sphere: centre x y z (i32 bits), threshold r2, lo x y z, hi x y z.
// occ: one bit per cell; cell (ix, iy, iz) is bit iz % 32 of word (ix * res + iy) * words_per_column + iz / 32.

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

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> spheres: array<u32>;
@group(0) @binding(2) var<storage, read_write> occ: array<atomic<u32>>;
// One bit per block of 8^3 cells that a single sphere holds entirely (same layout as occ).
@group(0) @binding(3) var<storage, read_write> covered: array<atomic<u32>>;

const SUBCELLS: u32 = 16u;
const BLOCK: u32 = 8u;

// The PCG output permutation (O'Neill 2014), as lattice.rs's pcg_hash.
fn pcg_hash(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// Floor of sqrt(v), exact for every u32.
fn isqrt(v: u32) -> u32 {
    var r = min(u32(sqrt(f32(v))), 65535u);
    while (r * r > v) {
        r = r - 1u;
    }
    while (r < 65535u && (r + 1u) * (r + 1u) <= v) {
        r = r + 1u;
    }
    return r;
}

// Floor division by a positive divisor (WGSL's / truncates toward zero).
fn floor_div(a: i32, b: i32) -> i32 {
    return select(a / b, (a - b + 1) / b, a < 0);
}

// Nearest and farthest squared lattice distance along an axis from cell i's lattice points
// (16 i .. 16 i + 15) to the centre coordinate c.
fn near_far(i: u32, c: i32) -> vec2<u32> {
    let a = i32(i * SUBCELLS) - c;
    let b = a + i32(SUBCELLS) - 1;
    let far = max(abs(a), abs(b));
    let near = select(min(abs(a), abs(b)), 0, a <= 0 && b >= 0);
    return vec2<u32>(u32(near * near), u32(far * far));
}

// Sets bits z0..=z1 of a column with one atomicOr per word.
fn set_run(column: u32, z0: u32, z1: u32) {
    for (var w = z0 / 32u; w <= z1 / 32u; w = w + 1u) {
        let first = max(z0, w * 32u) - w * 32u;
        let last = min(z1, w * 32u + 31u) - w * 32u;
        let upper = select((1u << (last + 1u)) - 1u, 0xffffffffu, last == 31u);
        atomicOr(&occ[column + w], upper & ~((1u << first) - 1u));
    }
}

// Sets bits z0..=z1 of a column of the covered-block grid.
fn set_block_run(column: u32, z0: u32, z1: u32) {
    for (var w = z0 / 32u; w <= z1 / 32u; w = w + 1u) {
        let first = max(z0, w * 32u) - w * 32u;
        let last = min(z1, w * 32u + 31u) - w * 32u;
        let upper = select((1u << (last + 1u)) - 1u, 0xffffffffu, last == 31u);
        atomicOr(&covered[column + w], upper & ~((1u << first) - 1u));
    }
}

fn is_covered(column: u32, bz: u32) -> bool {
    return ((atomicLoad(&covered[column + bz / 32u]) >> (bz % 32u)) & 1u) == 1u;
}

// Farthest squared lattice distance along an axis from cells first..=last to the centre c.
fn far_range(first: u32, last: u32, c: i32) -> u32 {
    let a = i32(first * SUBCELLS) - c;
    let b = i32((last + 1u) * SUBCELLS) - 1 - c;
    let far = max(abs(a), abs(b));
    return u32(far * far);
}

// A sphere on the lattice (lattice.rs's QSphere): centre, threshold, candidate cell range.
struct QSphere {
    c: vec3<i32>,
    r2: u32,
    lo: vec3<u32>,
    hi: vec3<u32>,
}

fn load_sphere(s: u32) -> QSphere {
    let b = s * 10u;
    return QSphere(
        vec3<i32>(bitcast<i32>(spheres[b]), bitcast<i32>(spheres[b + 1u]), bitcast<i32>(spheres[b + 2u])),
        spheres[b + 3u],
        vec3<u32>(spheres[b + 4u], spheres[b + 5u], spheres[b + 6u]),
        vec3<u32>(spheres[b + 7u], spheres[b + 8u], spheres[b + 9u]),
    );
}

// The work item of an invocation of the block passes: sphere gid.x (plus the chunk's offset) and
// its gid.y-th x slab of blocks; ok is false when there is none.
struct BlockSlab {
    q: QSphere,
    bx: u32,
    ok: bool,
}

fn block_slab(gid: vec3<u32>) -> BlockSlab {
    let s = gid.x + params.sphere_offset;
    if (s >= params.n_spheres) {
        return BlockSlab(QSphere(vec3<i32>(0), 0u, vec3<u32>(1u), vec3<u32>(0u)), 0u, false);
    }
    let q = load_sphere(s);
    let bx = q.lo.x / BLOCK + gid.y;
    let ok = q.lo.x <= q.hi.x && q.lo.y <= q.hi.y && q.lo.z <= q.hi.z && bx <= q.hi.x / BLOCK;
    return BlockSlab(q, bx, ok);
}

// Pass 1: per (sphere, x column of blocks), the run of z blocks whose every lattice point is inside.
@compute @workgroup_size(64, 1, 1)
fn cover_blocks(@builtin(global_invocation_id) gid: vec3<u32>) {
    let slab = block_slab(gid);
    if (!slab.ok) {
        return;
    }
    let q = slab.q;
    let bx = slab.bx;
    let res = params.res;
    let fx = far_range(bx * BLOCK, min((bx + 1u) * BLOCK, res) - 1u, q.c.x);
    if (fx > q.r2) {
        return;
    }
    let span = i32(BLOCK * SUBCELLS);
    for (var by = q.lo.y / BLOCK; by <= q.hi.y / BLOCK; by = by + 1u) {
        let fy = far_range(by * BLOCK, min((by + 1u) * BLOCK, res) - 1u, q.c.y);
        if (fx + fy > q.r2) {
            continue;
        }
        // Full-size blocks entirely inside in z (a smaller last block may be missed: only costs time).
        let h = i32(isqrt(q.r2 - fx - fy));
        let blo = max(0, floor_div(q.c.z - h + span - 1, span));
        let bhi = min(i32(params.n_blocks) - 1, floor_div(q.c.z + h - (span - 1), span));
        if (blo <= bhi) {
            set_block_run((bx * params.n_blocks + by) * params.block_words_per_column, u32(blo), u32(bhi));
        }
    }
}

// Pass 3: every cell of every covered block is occupied. One invocation per column of cells.
@compute @workgroup_size(8, 8, 1)
fn fill_covered(@builtin(global_invocation_id) gid: vec3<u32>) {
    let res = params.res;
    if (gid.x >= res || gid.y >= res) {
        return;
    }
    let block_column = ((gid.x / BLOCK) * params.n_blocks + gid.y / BLOCK) * params.block_words_per_column;
    let column = (gid.x * res + gid.y) * params.words_per_column;
    for (var w = 0u; w < params.block_words_per_column; w = w + 1u) {
        var bits = atomicLoad(&covered[block_column + w]);
        while (bits != 0u) {
            let bz = w * 32u + firstTrailingBit(bits);
            bits = bits & (bits - 1u);
            set_run(column, bz * BLOCK, min(bz * BLOCK + BLOCK - 1u, res - 1u));
        }
    }
}

// Tests cells z0..=z1 of column (ix, iy) at their jittered samples.
fn test_cells(column: u32, ix: u32, iy: u32, z0: i32, z1: i32, c: vec3<i32>, r2: u32) {
    if (z0 > z1) {
        return;
    }
    let res = params.res;
    var word = u32(z0) / 32u;
    var bits = 0u;
    for (var z = z0; z <= z1; z = z + 1) {
        let iz = u32(z);
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

// Nearest squared lattice distance along an axis from cells first..=last to the centre c.
fn near_range(first: u32, last: u32, c: i32) -> u32 {
    let a = i32(first * SUBCELLS) - c;
    let b = i32((last + 1u) * SUBCELLS) - 1 - c;
    let near = select(min(abs(a), abs(b)), 0, a <= 0 && b >= 0);
    return u32(near * near);
}

// Cells z0..=z1 of column (ix, iy) against sphere q: candidates are the cells whose nearest lattice
// point can be inside; the run whose farthest lattice point is inside is set without testing; the
// rest are tested at their jittered sample.
fn raster_column(q: QSphere, ix: u32, iy: u32, z0_in: u32, z1_in: u32) {
    let nfx = near_far(ix, q.c.x);
    let nfy = near_far(iy, q.c.y);
    if (nfx.x + nfy.x > q.r2) {
        return;
    }
    let sub = i32(SUBCELLS);
    let reach = i32(isqrt(q.r2 - nfx.x - nfy.x));
    let z0 = max(i32(z0_in), floor_div(q.c.z - reach, sub));
    let z1 = min(i32(z1_in), floor_div(q.c.z + reach, sub));
    if (z0 > z1) {
        return;
    }
    let column = (ix * params.res + iy) * params.words_per_column;
    var full_lo = 1;
    var full_hi = 0;
    if (nfx.y + nfy.y <= q.r2) {
        let h = i32(isqrt(q.r2 - nfx.y - nfy.y));
        full_lo = max(z0, floor_div(q.c.z - h + sub - 1, sub));
        full_hi = min(z1, floor_div(q.c.z + h - (sub - 1), sub));
    }
    if (full_lo <= full_hi) {
        set_run(column, u32(full_lo), u32(full_hi));
        test_cells(column, ix, iy, z0, full_lo - 1, q.c, q.r2);
        test_cells(column, ix, iy, full_hi + 1, z1, q.c, q.r2);
    } else {
        test_cells(column, ix, iy, z0, z1, q.c, q.r2);
    }
}

// Pass 2: per (sphere, x slab of blocks), the cells of the blocks it reaches that no sphere covers.
@compute @workgroup_size(64, 1, 1)
fn raster_spheres(@builtin(global_invocation_id) gid: vec3<u32>) {
    let slab = block_slab(gid);
    if (!slab.ok) {
        return;
    }
    let q = slab.q;
    let bx = slab.bx;
    let x0 = max(q.lo.x, bx * BLOCK);
    let x1 = min(q.hi.x, bx * BLOCK + BLOCK - 1u);
    let nx = near_range(x0, x1, q.c.x);
    if (nx > q.r2) {
        return;
    }
    let bz_lo = q.lo.z / BLOCK;
    let bz_hi = q.hi.z / BLOCK;
    for (var by = q.lo.y / BLOCK; by <= q.hi.y / BLOCK; by = by + 1u) {
        let y0 = max(q.lo.y, by * BLOCK);
        let y1 = min(q.hi.y, by * BLOCK + BLOCK - 1u);
        let ny = near_range(y0, y1, q.c.y);
        if (nx + ny > q.r2) {
            continue;
        }
        let block_column = (bx * params.n_blocks + by) * params.block_words_per_column;
        for (var w = bz_lo / 32u; w <= bz_hi / 32u; w = w + 1u) {
            let first = max(bz_lo, w * 32u) - w * 32u;
            let last = min(bz_hi, w * 32u + 31u) - w * 32u;
            let range = select((1u << (last + 1u)) - 1u, 0xffffffffu, last == 31u) & ~((1u << first) - 1u);
            var open = ~atomicLoad(&covered[block_column + w]) & range;
            while (open != 0u) {
                let bz = w * 32u + firstTrailingBit(open);
                open = open & (open - 1u);
                let z0 = max(q.lo.z, bz * BLOCK);
                let z1 = min(q.hi.z, bz * BLOCK + BLOCK - 1u);
                if (nx + ny + near_range(z0, z1, q.c.z) > q.r2) {
                    continue;
                }
                for (var ix = x0; ix <= x1; ix = ix + 1u) {
                    for (var iy = y0; iy <= y1; iy = iy + 1u) {
                        raster_column(q, ix, iy, z0, z1);
                    }
                }
            }
        }
    }
}
