//! `Grid` and `SdfSamples` construction from arbitrary numbers: an error or valid samples whose
//! accessors (positions, bounds, spheres, sign balance) never panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use rfta_geom::{Grid, SdfSamples, glam::DVec3};

fn f64s(bytes: &[u8]) -> Vec<f64> {
    bytes
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().unwrap_or([0; 8])))
        .collect()
}

fn exercise(s: &SdfSamples) {
    let _ = s.bounds();
    let _ = s.sign_balance();
    for i in 0..s.len().min(64) {
        let sphere = s.sphere(i);
        assert!(sphere.radius >= 0.0 && sphere.radius.is_finite());
        assert!(s.position(i).is_finite());
    }
}

fuzz_target!(|data: &[u8]| {
    let Some((&mode, rest)) = data.split_first() else {
        return;
    };
    if mode % 2 == 0 {
        // Grid: 3 dimension bytes, then origin, spacing and values as f64.
        if rest.len() < 3 {
            return;
        }
        let dims = [rest[0] as usize % 9, rest[1] as usize % 9, rest[2] as usize % 9];
        let nums = f64s(&rest[3..]);
        if nums.len() < 6 {
            return;
        }
        let origin = DVec3::new(nums[0], nums[1], nums[2]);
        let spacing = DVec3::new(nums[3], nums[4], nums[5]);
        let values = nums[6..].to_vec();
        let grid = if mode % 4 == 0 {
            Grid::new(dims, origin, spacing)
        } else {
            Grid::from_bounds(dims, origin, spacing)
        };
        if let Ok(grid) = grid {
            assert!(grid.len() > 0);
            assert!(grid.bounds().min.is_finite());
            if let Ok(s) = SdfSamples::grid(grid, values) {
                exercise(&s);
            }
        }
    } else {
        // Scattered: rows of x y z s.
        let nums = f64s(rest);
        let (positions, values) = nums
            .chunks_exact(4)
            .map(|r| (DVec3::new(r[0], r[1], r[2]), r[3]))
            .unzip();
        if let Ok(s) = SdfSamples::scattered(positions, values) {
            exercise(&s);
        }
    }
});
