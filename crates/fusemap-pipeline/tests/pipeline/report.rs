//! `report.html` in a real browser: headless Chromium (Debian's `chromium`, installed by
//! `scripts/test`) renders the page `fusemap validate` writes on the production line; the
//! rendered document holds every section and the pictures inline, and a screenshot of
//! the whole page is taken. Without Chromium the test skips (a failure under `FUSEMAP_NO_SKIP=1`).

use crate::validation::{bag, config};
use fusemap_pipeline::outputs::{REPORT_HTML, REPORT_SECTIONS};
use fusemap_pipeline::validate::ValidateJob;
use std::path::Path;
use std::process::Command;

const CHROMIUM: &str = "/usr/bin/chromium";

/// Chromium headless with the flags this machine needs: no sandbox (tests run as root),
/// no GPU, and none of the background connections a closed network refuses.
fn chromium(profile: &Path, args: &[&str]) -> std::process::Output {
    Command::new(CHROMIUM)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--hide-scrollbars",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .args(args)
        .output()
        .expect("chromium runs")
}

#[test]
fn the_report_renders_every_section_in_a_browser() {
    if !Path::new(CHROMIUM).is_file() {
        fusemap_io::testdata::skip("no Chromium at /usr/bin/chromium (scripts/test installs Debian's chromium)");
        return;
    }
    let dir = fusemap_io::testdata::fixture_dir(env!("CARGO_TARGET_TMPDIR"), "report");
    let cfg = dir.join("config.toml");
    std::fs::write(&cfg, config((0.25, 0.0), 0.0)).unwrap();
    let out = dir.join("out");
    ValidateJob::plan(Some(&cfg), bag(), &out).unwrap().run(&mut |_| {}).unwrap();
    let page = out.join(REPORT_HTML);
    let html = std::fs::read_to_string(&page).unwrap();
    // Self-contained: nothing is fetched.
    assert!(!html.contains("http://") && !html.contains("https://") && !html.contains("<script"));
    let url = format!("file://{}", page.display());
    // The DOM after rendering: each section, the verdict, the pictures as inline PNGs.
    let dom = chromium(&dir.join("profile-dom"), &["--dump-dom", &url]);
    assert!(dom.status.success(), "{}", String::from_utf8_lossy(&dom.stderr));
    let dom = String::from_utf8_lossy(&dom.stdout);
    for id in REPORT_SECTIONS {
        assert!(dom.contains(&format!("<section id=\"{id}\">")), "section {id} missing from the rendered page");
    }
    for needle in ["fusion_helps", "no_gain", "check_sync_and_extrinsics"] {
        if html.contains(needle) {
            assert!(dom.contains(needle));
        }
    }
    assert!(dom.matches("<img ").count() >= 2 && dom.contains("data:image/png;base64,iVBOR"));
    // The estimator's consistency over time: its GNSS fixes' NIS, plotted.
    assert!(dom.contains("GNSS fixes: mean NIS"), "no NIS over time in the estimator's section");
    let shot = dir.join("report.png");
    let _ = std::fs::remove_file(&shot);
    let run = chromium(
        &dir.join("profile-shot"),
        &["--window-size=1200,3000", &format!("--screenshot={}", shot.display()), &url],
    );
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let png = std::fs::read(&shot).unwrap();
    assert!(png.starts_with(b"\x89PNG") && png.len() > 50_000, "a screenshot of {} bytes", png.len());
}
