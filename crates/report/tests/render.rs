//! The report as a browser shows it: headless Chromium must render report.html to a non-blank
//! screenshot, and every image must be an inline PNG that decodes.
//!
//! Without Chromium the test is skipped with a notice, except under CI (env `CI` set), where
//! .ci/run installs it and a missing browser is a failure.

mod common;

use base64::Engine;
use common::synthetic::{write_run, Kind, TempDir};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};
use vicpilco_report::write_report;

fn find_on_path(names: &[&str]) -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .flat_map(|dir| names.iter().map(move |n| dir.join(n)))
        .find(|p| p.is_file())
}

/// Chromium refuses its sandbox as root.
fn is_root() -> bool {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            let uid = s.lines().find(|l| l.starts_with("Uid:"))?;
            uid.split_whitespace().nth(1).map(|u| u == "0")
        })
        .unwrap_or(false)
}

/// Decodes a PNG to 8-bit RGB(A) samples; returns (width, height, channels, samples).
fn decode_png(bytes: &[u8]) -> (u32, u32, usize, Vec<u8>) {
    let mut decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    decoder.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
    let mut reader = decoder.read_info().expect("PNG header");
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).expect("PNG data");
    buf.truncate(info.buffer_size());
    let channels = info.color_type.samples();
    (info.width, info.height, channels, buf)
}

/// Checks every `<img>` of the page is an inline PNG that decodes; returns how many.
fn check_inline_images(page: &str) -> usize {
    let tag = regex::Regex::new(r#"(?is)<img\b[^>]*>"#).unwrap();
    let src = regex::Regex::new(r#"(?is)\bsrc\s*=\s*"([^"]*)""#).unwrap();
    let tags: Vec<&str> = tag.find_iter(page).map(|m| m.as_str()).collect();
    // A tag the first pattern missed (say, a `>` inside an attribute) would escape the check.
    assert_eq!(
        tags.len(),
        page.to_ascii_lowercase().matches("<img").count()
    );
    for t in &tags {
        let s = src
            .captures(t)
            .unwrap_or_else(|| panic!("img without src: {t}"))[1]
            .to_string();
        let data = s
            .strip_prefix("data:image/png;base64,")
            .unwrap_or_else(|| panic!("img src is not an inline PNG: {}", &s[..s.len().min(60)]));
        let bytes = base64::engine::general_purpose::STANDARD
            .decode(data)
            .expect("img src is valid base64");
        assert!(!bytes.is_empty());
        let (w, h, _, _) = decode_png(&bytes);
        assert!(w > 100 && h > 100, "tiny image {w}x{h}");
    }
    tags.len()
}

/// Runs `cmd`, killing it if it has not finished after `limit`.
fn run_with_limit(mut cmd: Command, limit: Duration) -> std::process::ExitStatus {
    let mut child = cmd
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("start chromium");
    let start = Instant::now();
    loop {
        if let Some(status) = child.try_wait().expect("wait for chromium") {
            return status;
        }
        if start.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            panic!("chromium did not finish within {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(100));
    }
}

fn screenshot(chromium: &Path, html: &Path, out: &Path, profile: &Path) {
    let mut cmd = Command::new(chromium);
    cmd.args([
        "--headless",
        "--disable-gpu",
        "--hide-scrollbars",
        "--no-first-run",
    ]);
    if is_root() {
        cmd.arg("--no-sandbox");
    }
    cmd.arg(format!("--user-data-dir={}", profile.display()))
        .arg(format!("--screenshot={}", out.display()))
        .arg("--window-size=1280,4000")
        .arg(format!("file://{}", html.display()));
    let status = run_with_limit(cmd, Duration::from_secs(180));
    assert!(status.success(), "chromium exited with {status}");
}

#[test]
fn report_renders_in_headless_chromium() {
    let tmp = TempDir::new("render");
    write_run(tmp.path(), Kind::ViltaVar);
    let files = write_report(tmp.path()).expect("write_report");
    let page = std::fs::read_to_string(&files.html).unwrap();
    let pngs = files
        .images
        .iter()
        .filter(|p| p.extension().is_some_and(|e| e == "png"))
        .count();
    assert_eq!(check_inline_images(&page), pngs);
    assert_eq!(pngs, 8);

    let Some(chromium) = find_on_path(&["chromium", "chromium-browser"]) else {
        if std::env::var_os("CI").is_some() {
            panic!("CI is set but neither chromium nor chromium-browser is on PATH (.ci/run installs it)");
        }
        eprintln!("skipping the browser check: chromium is not on PATH (apt-get install chromium)");
        return;
    };
    let profile = tmp.path().join("chromium-profile");
    let shot = tmp.path().join("shot.png");
    screenshot(&chromium, &files.html, &shot, &profile);
    let fraction = not_white(&shot);
    eprintln!("{:.1} % of the screenshot is not white", 100.0 * fraction);
    assert!(
        fraction > 0.05,
        "blank-looking page: only {:.2} % not white",
        100.0 * fraction
    );

    // The control: an empty page must measure as blank, or the check above proves nothing.
    let empty = tmp.path().join("empty.html");
    std::fs::write(&empty, "<!DOCTYPE html><html><body></body></html>").unwrap();
    let shot = tmp.path().join("empty.png");
    screenshot(&chromium, &empty, &shot, &profile);
    assert!(not_white(&shot) < 0.001);
}

/// The fraction of a screenshot's pixels that are not pure white.
fn not_white(shot: &Path) -> f64 {
    let (w, h, channels, px) = decode_png(&std::fs::read(shot).expect("screenshot written"));
    assert!(w >= 1000 && h >= 1000, "screenshot is {w}x{h}");
    let count = px
        .chunks_exact(channels)
        .filter(|p| p[..channels.min(3)].iter().any(|&c| c != 255))
        .count();
    count as f64 / (w as f64 * h as f64)
}
