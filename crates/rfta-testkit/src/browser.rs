//! Headless Chromium for the page tests: finding it, opening a page with the network off, and
//! reading a screenshot's pixels.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Chromium (`RFTA_CHROMIUM`, or found on the PATH); `None`, said on stderr, where there is
/// none, which CI (`CI` set) does not allow: there a missing browser panics.
#[expect(
    clippy::print_stderr,
    reason = "the caller's test says when it was skipped"
)]
pub fn chromium(test: &str) -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("RFTA_CHROMIUM") {
        return Some(PathBuf::from(p));
    }
    let found = ["chromium", "chromium-browser", "google-chrome"]
        .into_iter()
        .find(|name| {
            Command::new(name)
                .arg("--version")
                .output()
                .is_ok_and(|o| o.status.success())
        })
        .map(PathBuf::from);
    if found.is_none() {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI needs Chromium for the page tests (apt-get install chromium)"
        );
        eprintln!("SKIPPED {test}: no Chromium");
    }
    found
}

/// Chromium headless on `url` with the network off (every host name unresolvable; loopback
/// addresses still answer), software WebGL and a window of `size` (width, height), to add
/// arguments to and start.
pub fn command(browser: &Path, url: &str, size: (u32, u32)) -> Command {
    let mut c = Command::new(browser);
    c.args([
        "--headless=new",
        "--no-sandbox",
        "--disable-gpu",
        "--enable-unsafe-swiftshader",
        "--use-angle=swiftshader",
        "--host-resolver-rules=MAP * ~NOTFOUND, EXCLUDE 127.0.0.1",
        &format!("--window-size={},{}", size.0, size.1),
    ])
    .arg(url);
    c
}

/// [`command`] with `budget_ms` of virtual time, doing `what` (`--dump-dom`, or
/// `--screenshot=PATH`), run to its end. (Virtual time stops the page's clocks while its
/// scripts run: timings need a real-time run of [`command`].)
///
/// # Errors
/// When Chromium cannot be started.
pub fn open(
    browser: &Path,
    url: &str,
    size: (u32, u32),
    budget_ms: u32,
    what: &str,
) -> std::io::Result<Output> {
    command(browser, url, size)
        .args([
            format!("--virtual-time-budget={budget_ms}"),
            what.to_string(),
        ])
        .output()
}

/// The pixels of an RGB(A) PNG: width, height, and each one's RGB.
///
/// # Errors
/// When the file cannot be read or is not a PNG.
pub fn pixels(png: &Path) -> Result<(usize, usize, Vec<[u8; 3]>), String> {
    let file = std::fs::File::open(png).map_err(|e| format!("{}: {e}", png.display()))?;
    let decoder = png::Decoder::new(std::io::BufReader::new(file));
    let mut reader = decoder
        .read_info()
        .map_err(|e| format!("{}: {e}", png.display()))?;
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader
        .next_frame(&mut buf)
        .map_err(|e| format!("{}: {e}", png.display()))?;
    let step = info.color_type.samples();
    let rgb = buf[..info.buffer_size()]
        .chunks(step)
        .map(|p| [p[0], p[1], p[2]])
        .collect();
    Ok((info.width as usize, info.height as usize, rgb))
}
