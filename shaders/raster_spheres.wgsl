// Sphere occupancy on an integer lattice (rfta-raster, GPU path).
//
// One invocation per (sphere, x slab of its candidate cells). Per column of cells: the candidates
// are the cells whose nearest lattice point can be inside, the run of cells whose farthest lattice
// point is inside is set without testing, and the other candidates are tested at their jittered
// sample with integer arithmetic, 32 cells per atomicOr. The CPU path (crates/rfta-raster/src/cpu.rs)
// uses the same hash, lattice and test, so both produce the same bits.
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
    let nfx = near_far(ix, c.x);
    if (nfx.x > r2) {
        return;
    }
    let sub = i32(SUBCELLS);
    for (var iy = lo.y; iy <= hi.y; iy = iy + 1u) {
        let nfy = near_far(iy, c.y);
        if (nfx.x + nfy.x > r2) {
            continue;
        }
        let column = (ix * params.res + iy) * params.words_per_column;
        // Candidates: cells whose nearest lattice point can be inside.
        let reach = i32(isqrt(r2 - nfx.x - nfy.x));
        let z0 = max(i32(lo.z), floor_div(c.z - reach, sub));
        let z1 = min(i32(hi.z), floor_div(c.z + reach, sub));
        if (z0 > z1) {
            continue;
        }
        // The run of cells whose farthest lattice point is inside needs no test.
        var full_lo = 1;
        var full_hi = 0;
        if (nfx.y + nfy.y <= r2) {
            let h = i32(isqrt(r2 - nfx.y - nfy.y));
            full_lo = max(z0, floor_div(c.z - h + sub - 1, sub));
            full_hi = min(z1, floor_div(c.z + h - (sub - 1), sub));
        }
        if (full_lo <= full_hi) {
            set_run(column, u32(full_lo), u32(full_hi));
            test_cells(column, ix, iy, z0, full_lo - 1, c, r2);
            test_cells(column, ix, iy, full_hi + 1, z1, c, r2);
        } else {
            test_cells(column, ix, iy, z0, z1, c, r2);
        }
    }
}
