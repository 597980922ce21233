//! The run report (`OUT/report.html`, src/report): through the real binary, every file it
//! references exists, failed nodes show as failed, thumbnails have the thumbnail size, and
//! in a real browser (headless Debian `chromium`) the page renders, every image loads and
//! the console stays clean.

use crate::common::{asset, skip_or_fail};
use std::path::{Path, PathBuf};
use std::process::Command;

/// Runs `cgnodes ARGS` and returns its stderr, failing on an exit code other than `want`.
fn cgnodes(args: &[&str], want: i32) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_cgnodes"))
        .args(args)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert_eq!(out.status.code(), Some(want), "cgnodes {args:?}: {err}");
    err
}

/// Every `src="..."` and `href="..."` value of an HTML page.
fn references(html: &str) -> Vec<String> {
    let mut v = Vec::new();
    for attr in ["src=\"", "href=\""] {
        let mut rest = html;
        while let Some(i) = rest.find(attr) {
            let tail = &rest[i + attr.len()..];
            let end = tail.find('"').unwrap();
            v.push(tail[..end].to_string());
            rest = &tail[end..];
        }
    }
    v
}

/// Checks that every file the report in `dir` references exists; returns the referenced
/// thumbnails and animations under report_files/.
fn check_references(dir: &Path) -> Vec<PathBuf> {
    let html = std::fs::read_to_string(dir.join("report.html")).unwrap();
    assert!(html.starts_with("<!DOCTYPE html>") && html.trim_end().ends_with("</html>"));
    let mut own = Vec::new();
    for r in references(&html) {
        assert!(!r.starts_with("file:") && !r.starts_with('/'), "{r}");
        let p = dir.join(r.replace("%20", " "));
        assert!(
            p.is_file(),
            "report.html references missing {}",
            p.display()
        );
        if r.starts_with("report_files/") {
            own.push(p);
        }
    }
    own
}

#[test]
fn run_report_shows_outputs_and_the_failed_node() {
    let dir = tempfile::tempdir().unwrap();
    let img = asset("assets/images/lena.png");
    let graph = serde_json::json!({
        "format": "cgnodes-graph", "version": 1,
        "nodes": {
            "img": {"type": "image_load", "params": {"path": img}},
            "save": {"type": "image_save", "inputs": {"image": "img.image"}, "params": {"path": "copy.png"}},
            "warp": {"type": "image_warp", "inputs": {"image": "img.image"}},
            "save_warp": {"type": "image_save", "inputs": {"image": "warp.image"}, "params": {"path": "warped.png"}},
            "grid": {"type": "mesh_grid", "params": {"cells_u": 4, "cells_v": 4}},
            "mesh": {"type": "mesh_save", "inputs": {"mesh": "grid.mesh"}, "params": {"path": "grid.obj"}}
        }
    });
    let gpath = dir.path().join("g.json");
    std::fs::write(&gpath, graph.to_string()).unwrap();
    let out = dir.path().join("out");
    let err = cgnodes(
        &[
            "run",
            gpath.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ],
        1,
    );
    assert!(err.contains("report:"), "{err}");
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    // The failed node and the writer it blocks, coloured as such in the graph.
    assert!(
        html.contains("<g class=\"node failed\" data-node=\"warp\"><title>warp (image_warp)"),
        "{html}"
    );
    assert!(html.contains("<g class=\"node blocked\" data-node=\"save_warp\"><title>save_warp"));
    assert!(html.contains("node 'warp' (image_warp) failed"));
    let own = check_references(&out);
    // Two thumbnails: the copied image and the mesh preview.
    assert_eq!(own.len(), 2, "{own:?}");
    let src = image::image_dimensions(&img).unwrap();
    let want = cgnodes::report::fit_thumbnail(src);
    assert!(want.0 <= 256 && want.1 <= 256 && (want.0 == 256 || want.1 == 256));
    let thumb = own
        .iter()
        .find(|p| image::image_dimensions(p).unwrap() == want);
    assert!(thumb.is_some(), "no thumbnail of {want:?} among {own:?}");
    // The mesh preview shows the mesh: pixels other than the background.
    let preview = own.iter().find(|p| Some(*p) != thumb).unwrap();
    let p = image::open(preview).unwrap().to_rgba8();
    let bg = *p.get_pixel(0, 0);
    assert!(p.pixels().filter(|q| **q != bg).count() > 1000);
    // --no-report writes none.
    let out2 = dir.path().join("out2");
    cgnodes(
        &[
            "run",
            gpath.to_str().unwrap(),
            "--out",
            out2.to_str().unwrap(),
            "--no-report",
            "-q",
        ],
        1,
    );
    assert!(out2.join("copy.png").is_file() && !out2.join("report.html").exists());
}

/// Opens `page` in headless chromium: the dumped DOM (after the load event) and the console
/// messages on stderr.
fn chromium(page: &Path, extra: &[&str]) -> Option<(String, String)> {
    let url = format!("file://{}", page.canonicalize().unwrap().display());
    let profile = tempfile::tempdir().unwrap();
    let out = Command::new("chromium")
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--allow-file-access-from-files",
            "--enable-logging=stderr",
            "--virtual-time-budget=3000",
            "--window-size=1200,900",
        ])
        .arg(format!("--user-data-dir={}", profile.path().display()))
        .args(extra)
        .arg(url)
        .output()
        .ok()?;
    Some((
        String::from_utf8_lossy(&out.stdout).to_string(),
        String::from_utf8_lossy(&out.stderr).to_string(),
    ))
}

#[test]
fn reports_render_in_a_browser_with_every_image_loaded() {
    if Command::new("chromium").arg("--version").output().is_err() {
        skip_or_fail(
            "reports_render_in_a_browser_with_every_image_loaded",
            "chromium is not installed (apt-get install -y chromium)",
        );
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let g = |n: &str| asset(&format!("graphs/{n}")).to_string_lossy().to_string();
    let mut reports = Vec::new();
    for (name, frames) in [
        ("raster_textured_scene.json", None),
        ("cloth_sphere.json", None),
        // The first frames are enough for the page (the graph test runs them all).
        ("dam_break_2d.json", Some("0..8")),
    ] {
        let out = dir.path().join(name);
        let mut args = vec![
            "run".to_string(),
            g(name),
            "--out".into(),
            out.to_string_lossy().into(),
            "-q".into(),
        ];
        if let Some(f) = frames {
            args.extend(["--frames".into(), f.into()]);
        }
        let a: Vec<&str> = args.iter().map(String::as_str).collect();
        cgnodes(&a, 0);
        reports.push(out);
    }
    let sweep = dir.path().join("sweep");
    std::fs::create_dir_all(&sweep).unwrap();
    cgnodes(
        &[
            "sweep",
            &g("arithmetic.json"),
            "--vary",
            "radius.value=1,2,3",
            "--measure",
            "pi_r2.value",
            "--x",
            "radius.value",
            "--csv",
            sweep.join("areas.csv").to_str().unwrap(),
            "--plot",
            sweep.join("areas.svg").to_str().unwrap(),
        ],
        0,
    );
    reports.push(sweep);
    for out in &reports {
        let imgs = check_references(out);
        let page = out.join("report.html");
        let (dom, log) = chromium(&page, &["--dump-dom"]).expect("chromium runs");
        assert!(
            dom.contains("data-loaded="),
            "{}: page did not load: {log}",
            out.display()
        );
        // (The script that sets the mark names it too: look for the attribute.)
        let broken: Vec<&str> = dom
            .split("<img")
            .skip(1)
            .filter(|t| t.split('>').next().unwrap_or("").contains("data-broken"))
            .collect();
        assert!(
            broken.is_empty(),
            "{}: broken images {broken:?}",
            out.display()
        );
        let n = dom.matches("<img").count();
        assert!(n >= imgs.len().min(1), "{}", out.display());
        for l in log.lines() {
            assert!(
                !(l.contains("CONSOLE") || l.contains("Uncaught")),
                "{}: console: {l}",
                out.display()
            );
        }
    }
    // A screenshot of the cloth report is not blank.
    let shot = dir.path().join("shot.png");
    let arg = format!("--screenshot={}", shot.display());
    chromium(&reports[1].join("report.html"), &[&arg]).expect("chromium runs");
    let img = image::open(&shot).unwrap().to_rgb8();
    let first = *img.get_pixel(0, 0);
    let differing = img.pixels().filter(|p| **p != first).count();
    assert!(
        differing > 10_000,
        "screenshot nearly blank: {differing} pixels differ"
    );
}
