//! The pages `rfta view` and `rfta reconstruct --html` write, opened in headless Chromium with
//! the network off: the viewer reports a drawn frame, and the screenshot shows the mesh.
//!
//! Needs Chromium (Debian's `chromium`, or `RFTA_CHROMIUM`); skipped with a message where it is
//! missing, except under CI (`CI` set), where it is installed and a missing browser fails.

mod common;

use common::{rfta, s, stderr, temp};
use rfta_testkit::browser::{self, chromium};
use std::path::Path;
use std::process::Output;

/// Chromium headless on `page` with the network off ([`browser::open`]), doing `what`.
fn open(browser: &Path, page: &Path, what: &str) -> Output {
    browser::open(
        browser,
        &format!("file://{}", page.display()),
        (900, 600),
        10000,
        what,
    )
    .expect("run chromium")
}

/// The pixels of a screenshot ([`browser::pixels`]).
fn pixels(png: &Path) -> (usize, usize, Vec<[u8; 3]>) {
    browser::pixels(png).expect("the screenshot")
}

/// Pixels of an RGB(A) PNG: width, height, and whether each is (nearly) white.
fn white_pixels(png: &Path) -> (usize, usize, Vec<bool>) {
    let (w, h, rgb) = pixels(png);
    (
        w,
        h,
        rgb.iter().map(|p| p.iter().all(|&c| c > 235)).collect(),
    )
}

#[test]
fn a_report_page_draws_the_mesh_offline() {
    let Some(browser) = chromium("a_report_page_draws_the_mesh_offline") else {
        return;
    };
    let dir = temp("a_report_page_draws_the_mesh_offline");
    let (npy, mesh, page) = (dir.join("t.npy"), dir.join("t.ply"), dir.join("t.html"));
    let o = rfta(&["sample", "--shape", "torus", "--res", "16", "-o", s(&npy)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = rfta(&[
        "-q",
        "reconstruct",
        s(&npy),
        "-o",
        s(&mesh),
        "--html",
        s(&page),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(&page).expect("the page");
    assert!(text.contains("loops around thin handles") && text.contains("components"));

    // The viewer ran to its first frame without an error.
    let dom = open(&browser, &page, "--dump-dom");
    let dom = String::from_utf8_lossy(&dom.stdout);
    assert!(dom.contains("data-ready=\"1\""), "not drawn: {dom:.2000}");

    // The mesh fills part of the view (the left part of the window, the panel on the right),
    // around its centre; a blank canvas would be white.
    let shot = dir.join("t.png");
    let o = open(&browser, &page, &format!("--screenshot={}", shot.display()));
    assert!(shot.exists(), "{}", stderr(&o));
    let (w, h, white) = white_pixels(&shot);
    let view_w = w - 330;
    let drawn = (0..h)
        .flat_map(|y| (0..view_w).map(move |x| (x, y)))
        .filter(|&(x, y)| !white[y * w + x])
        .count();
    let share = drawn as f64 / (view_w * h) as f64;
    assert!(share > 0.05 && share < 0.9, "{share:.3} of the view drawn");
    let around_centre = (h / 2 - 60..h / 2 + 60)
        .flat_map(|y| (view_w / 2 - 60..view_w / 2 + 60).map(move |x| (x, y)))
        .filter(|&(x, y)| !white[y * w + x])
        .count();
    assert!(
        around_centre > 1000,
        "{around_centre} pixels drawn near the centre"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `rfta view` writes the page of any mesh: against its samples, with the marks and marching
/// cubes' layer; without them, the mesh and its figures only. It refuses to write over its mesh.
#[test]
fn view_writes_the_page_of_a_mesh() {
    let dir = temp("view");
    let (npy, mesh, page) = (dir.join("t.npy"), dir.join("t.obj"), dir.join("t.html"));
    let o = rfta(&[
        "sample",
        "--shape",
        "torus",
        "--res",
        "12",
        "-o",
        s(&npy),
        "--save-mesh",
        s(&mesh),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = rfta(&["view", s(&mesh), "--sdf", s(&npy), "-o", s(&page)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(&page).expect("the page");
    assert!(text.contains("marching cubes (same samples)") && text.contains("on the wrong side"));
    let o = rfta(&["view", s(&mesh), "-o", s(&page)]);
    assert!(o.status.success());
    let text = std::fs::read_to_string(&page).expect("the page");
    assert!(text.contains("genus") && !text.contains("marching cubes (same samples)"));
    let o = rfta(&["view", s(&mesh), "-o", s(&mesh)]);
    assert!(!o.status.success(), "wrote the page over its mesh");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A ball with a bubble inside it (a void the samples wall in, kept): the page opens seeing
/// through the surface, and the cavity's orange shows in the middle of the view, where the
/// bubble is.
#[test]
fn a_cavity_shows_where_it_is() {
    let Some(browser) = chromium("a_cavity_shows_where_it_is") else {
        return;
    };
    let dir = temp("a_cavity_shows_where_it_is");
    let (npy, mesh, page) = (dir.join("b.npy"), dir.join("b.ply"), dir.join("b.html"));
    let grid = rfta_geom::Grid::cube(20, -1.0, 1.0).expect("grid");
    let values: Vec<f64> = (0..grid.len())
        .map(|i| {
            let p = grid.position(i);
            (p.length() - 0.7).max(0.3 - p.length())
        })
        .collect();
    rfta_io::write_sdf_grid(&npy, &grid, &values).expect("write the grid");
    let o = rfta(&[
        "-q",
        "reconstruct",
        s(&npy),
        "-o",
        s(&mesh),
        "--html",
        s(&page),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let shot = dir.join("b.png");
    let o = open(&browser, &page, &format!("--screenshot={}", shot.display()));
    assert!(shot.exists(), "{}", stderr(&o));
    let (w, h, rgb) = pixels(&shot);
    let view_w = w - 330;
    // Orange seen through the blue-grey surface: red above blue (the surface alone has more blue
    // than red, the white background as much).
    let orange = |p: [u8; 3]| i32::from(p[0]) - i32::from(p[2]) > 25;
    let count = |x0: usize, x1: usize, y0: usize, y1: usize| {
        (y0..y1)
            .flat_map(|y| (x0..x1).map(move |x| (x, y)))
            .filter(|&(x, y)| orange(rgb[y * w + x]))
            .count()
    };
    let centre = count(view_w / 2 - 50, view_w / 2 + 50, h / 2 - 50, h / 2 + 50);
    let corners = count(0, 60, 0, 60) + count(view_w - 60, view_w, h - 60, h);
    assert!(
        centre > 2000,
        "{centre} orange pixels in the middle of the view"
    );
    assert_eq!(corners, 0, "orange in the view's corners");
    let _ = std::fs::remove_dir_all(&dir);
}
