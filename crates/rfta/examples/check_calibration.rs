//! The calibration of `rfta::check` (docs/hardening.md): how exact, noisy and non-distance fields
//! on a torus score at 17^3, 33^3 and 65^3 samples.
//!
//! `cargo run --release -p rfta --example check_calibration`
#![expect(clippy::print_stdout, reason = "an example prints its table")]

use rfta::check::inspect;
use rfta::geom::{Grid, SdfSamples, rng::Rng};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    println!("| field | samples | rho > 1.01 | rho > 1.25 | largest rho | clamp |");
    println!("|---|---|---|---|---|---|");
    for n in [16usize, 32, 64] {
        let grid = Grid::cube(n, -1.0, 1.0)?;
        let h = 2.0 / n as f64;
        let torus = |i: usize| {
            let p = grid.position(i);
            let ring = (p.x * p.x + p.y * p.y).sqrt() - 0.6;
            (ring * ring + p.z * p.z).sqrt() - 0.25
        };
        let exact: Vec<f64> = (0..grid.len()).map(torus).collect();
        let mut rng = Rng::new(7);
        let mut u = move || 2.0 * rng.next_f64() - 1.0;
        let cases: Vec<(&str, Vec<f64>)> = vec![
            ("exact SDF", exact.clone()),
            (
                "x (1 + 0.05 u)",
                exact.iter().map(|v| v * (1.0 + 0.05 * u())).collect(),
            ),
            (
                "+ 0.05 h u",
                exact.iter().map(|v| v + 0.05 * h * u()).collect(),
            ),
            ("+ 0.1 u", exact.iter().map(|v| v + 0.1 * u()).collect()),
            ("1.5 x", exact.iter().map(|v| 1.5 * v).collect()),
            ("random", exact.iter().map(|_| u()).collect()),
            ("occupancy", exact.iter().map(|v| v.signum()).collect()),
            (
                "clamped at 2h",
                exact.iter().map(|v| v.clamp(-2.0 * h, 2.0 * h)).collect(),
            ),
        ];
        for (name, values) in cases {
            let c = inspect(&SdfSamples::grid(grid, values)?);
            println!(
                "| {name} | {}^3 | {:.1}% | {:.1}% | {} | {} |",
                n + 1,
                100.0 * c.inconsistent_fraction(),
                100.0 * c.severe_fraction(),
                c.worst.map_or("-".into(), |w| format!("{:.3}", w.2)),
                c.clamp.map_or("-".into(), |(v, k)| format!("{v:.4} ({k})")),
            );
        }
    }
    Ok(())
}
