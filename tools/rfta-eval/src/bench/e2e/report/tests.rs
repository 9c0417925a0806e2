//! Tests of the bench report: its tables read from hand-made runs.

use super::*;

fn run(walls: &[f64], steals: &[f64]) -> Result<Run> {
    Ok(Run {
        wall: walls[(walls.len() - 1) / 2],
        cpu: 0.0,
        rss_mb: 0.0,
        chamfer: f64::NAN,
        faces: 0,
        watertight: true,
        walls: walls.to_vec(),
        steals: steals.to_vec(),
        hash: 0,
        simplified: f64::NAN,
    })
}

#[test]
fn the_share_table_sums_the_step_over_the_shapes() {
    let row = |n, method: &str, threads, wall: f64, simplified: f64| {
        let mut r = run(&[wall], &[0.0]).expect("a run");
        r.simplified = simplified;
        ("a".to_string(), n, method.to_string(), threads, Ok(r))
    };
    let rows = vec![
        // N = 20: (0.1 + 0.3) / (2 + 3) = 8%.
        row(20, "rfta-default", 2, 2.0, 0.1),
        row(20, "rfta-default", 2, 3.0, 0.3),
        // Neither the 1-thread run nor marching cubes (no step) counts.
        row(20, "rfta-default", 1, 1.0, 0.9),
        row(20, "mc", 1, 1.0, f64::NAN),
        // 129^3: 3 of 20 s, 15%.
        row(128, "rfta-default", 2, 20.0, 3.0),
    ];
    let mut s = String::new();
    simplification_share(&mut s, &rows, &[20, 128]).expect("written");
    assert!(s.contains("| 20 | 2 | 0.40 | 5.00 | 8.0% | met |"), "{s}");
    assert!(
        s.contains("| 128 | 1 | 3.00 | 20.00 | 15.0% | **not met** |"),
        "{s}"
    );
    let mut none = String::new();
    simplification_share(&mut none, &rows, &[50]).expect("written");
    assert!(none.is_empty());
}

#[test]
fn the_targets_table_says_which_targets_the_default_meets() {
    let row = |shape: &str, n, method: &str, threads, wall: f64, mb: f64| {
        let mut r = run(&[wall], &[0.0]).expect("a run");
        r.rss_mb = mb;
        (shape.to_string(), n, method.to_string(), threads, Ok(r))
    };
    let rows = vec![
        // N = 20: mean (0.2 + 0.3) / 2 = 0.25 s <= 0.3 s, no memory target.
        row("a", 20, "rfta-default", 2, 0.2, 900.0),
        row("b", 20, "rfta-default", 2, 0.3, 40.0),
        // Neither the 1-thread run nor another method counts.
        row("a", 20, "rfta-default", 1, 9.0, 40.0),
        row("a", 20, "mc", 1, 9.0, 40.0),
        // 129^3: fast enough, but 600 MB > 500 MB.
        row("bunny", 128, "rfta-default", 2, 2.0, 600.0),
        // N = 50: 1.5 s > 1 s.
        row("a", 50, "rfta-default", 2, 1.5, 10.0),
        // 257^3: 30 s > 20 s, but 1,900 MB <= 2,000 MB.
        row("bunny", 256, "rfta-default", 2, 30.0, 1900.0),
    ];
    let mut s = String::new();
    // Sizes this run did not have get no row: 256 only in the second table.
    targets(&mut s, &rows, &[20, 50, 128]).expect("written");
    assert!(!s.contains("| 256 |"), "{s}");
    targets(&mut s, &rows[6..], &[256]).expect("written");
    // 129^3 at 4 s > 3 s and 600 MB > 500 MB.
    targets(
        &mut s,
        &[row("c", 128, "rfta-default", 2, 4.0, 600.0)],
        &[128],
    )
    .expect("ok");
    for line in [
        "| 20 | 2 | 0.25 | 0.3 | 900 | - | met |",
        "| 50 | 1 | 1.50 | 1 | 10 | - | **time not met** |",
        "| 128 | 1 | 2.00 | 3 | 600 | 500 | **memory not met** |",
        "| 256 | 1 | 30.00 | 20 | 1900 | 2000 | **time not met** |",
        "| 128 | 1 | 4.00 | 3 | 600 | 500 | **neither met** |",
    ] {
        assert!(s.contains(line), "{line} in {s}");
    }
    let mut none = String::new();
    targets(&mut none, &rows, &[30]).expect("written");
    assert!(none.is_empty());
}

#[test]
fn ratios_have_two_decimals_below_ten_and_none_above() {
    assert_eq!(ratio(0.0712), "0.07");
    assert_eq!(ratio(3.456), "3.46");
    assert_eq!(ratio(849.6), "850");
}

#[test]
fn the_quiet_speed_up_leaves_out_runs_the_hypervisor_slowed() {
    let rows = vec![
        (
            "a".into(),
            20,
            "rfta".into(),
            1,
            run(&[1.0, 2.0, 3.0], &[0.0, 0.5, 0.01]),
        ),
        (
            "a".into(),
            20,
            "rfta".into(),
            2,
            run(&[0.5, 1.0, 2.0], &[0.3, 0.0, 0.0]),
        ),
    ];
    let s = Scaling::of(&rows, 20, "rfta").expect("one shape");
    // Quiet: 1.0 and 3.0 on one thread (median 1.0), 1.0 and 2.0 on two (median 1.0).
    assert_eq!(s.quiet, Some(((1.0, 1.0), 4)));
    assert_eq!(s.median, (2.0, 1.0));
    let rows = vec![
        ("a".into(), 20, "rfta".into(), 1, run(&[1.0], &[0.5])),
        ("a".into(), 20, "rfta".into(), 2, run(&[0.5], &[0.0])),
    ];
    let s = Scaling::of(&rows, 20, "rfta").expect("one shape");
    assert_eq!(s.quiet, None);
}

#[test]
fn the_speed_up_pairs_shapes_and_takes_medians_and_fastest_runs() {
    let row = |shape: &str, method: &str, threads, walls: &[f64]| {
        (
            shape.to_string(),
            20,
            method.to_string(),
            threads,
            run(walls, &[0.0; 3]),
        )
    };
    let rows = vec![
        row("a", "rfta", 1, &[1.0, 2.0, 3.0]),
        row("a", "rfta", 2, &[0.5, 1.0, 2.0]),
        row("b", "rfta", 1, &[3.0, 4.0, 9.0]),
        row("b", "rfta", 2, &[2.0, 2.0, 2.0]),
        // No 2-thread run: left out of the pairs.
        row("c", "rfta", 1, &[10.0, 10.0, 10.0]),
        row("a", "ceiling", 1, &[0.6, 0.6, 0.6]),
        row("a", "ceiling", 2, &[0.3, 0.3, 0.4]),
    ];
    let s = Scaling::of(&rows, 20, "rfta").expect("two shapes have both");
    assert_eq!((s.shapes, s.runs), (2, 3));
    // Medians (2 + 4) / 2 and (1 + 2) / 2; fastest (1 + 3) / 2 and (0.5 + 2) / 2.
    assert_eq!(s.median, (3.0, 1.5));
    assert_eq!(s.fastest, (2.0, 1.25));
    let c = Scaling::of(&rows, 20, "ceiling").expect("one shape");
    assert_eq!(c.median, (0.6, 0.3));
    assert!(Scaling::of(&rows, 30, "rfta").is_none());
    assert!(Scaling::of(&rows, 20, "mc").is_none());
    // Every run quiet: the quiet medians are the medians.
    assert_eq!(s.quiet, Some(((3.0, 1.5), 12)));
}
