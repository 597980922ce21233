//! `cgnodes serve` and `run --watch`: the page in a real browser (headless Debian chromium
//! over the DevTools protocol, `support::browser`) shows the nodes and outputs, a moved
//! slider reruns the graph and the new image appears, a broken edit shows its error on its
//! node; requests without the token or from a foreign `Host` or `Origin` are refused.

use crate::common::skip_or_fail;
use crate::support::browser::{chromium_available, graph_copy, serve, Browser};
use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Duration;

/// A copy of the README's Tutte graph in `dir`, reading the mesh from the repository.
fn tutte_graph(dir: &Path) -> PathBuf {
    let g = dir.join("tutte.json");
    graph_copy("graphs/tutte_cotangent_circle.json", &g);
    g
}

/// One raw HTTP/1.1 request; returns the status code and the whole response.
fn request(port: u16, head: &str) -> (u16, String) {
    let mut s = TcpStream::connect(("127.0.0.1", port)).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
    s.write_all(head.as_bytes()).unwrap();
    let mut out = String::new();
    let _ = s.read_to_string(&mut out);
    let code = out
        .split_whitespace()
        .nth(1)
        .and_then(|c| c.parse().ok())
        .unwrap_or(0);
    (code, out)
}

#[test]
fn serve_refuses_requests_without_the_token_or_from_another_host_or_site() {
    let dir = tempfile::tempdir().unwrap();
    let g = tutte_graph(dir.path());
    let s = serve(&g, &dir.path().join("out"));
    let (p, t) = (s.port, &s.token);
    let get = |path: &str, extra: &str| {
        request(
            p,
            &format!(
                "GET {path} HTTP/1.1\r\nHost: 127.0.0.1:{p}\r\n{extra}Connection: close\r\n\r\n"
            ),
        )
    };
    // The right token, in the URL: the page, and the token as a cookie for this port.
    let (code, resp) = get(&format!("/?token={t}"), "");
    assert_eq!(code, 200);
    assert!(resp.contains(&format!("cgnodes_token_{p}={t}; HttpOnly; SameSite=Strict")));
    // Later requests carry the cookie.
    assert_eq!(
        get("/api/graph", &format!("Cookie: cgnodes_token_{p}={t}\r\n")).0,
        200
    );
    // No token, a wrong one, or another port's cookie.
    assert_eq!(get("/", "").0, 403);
    assert_eq!(
        get("/api/state?token=00000000000000000000000000000000", "").0,
        403
    );
    assert_eq!(
        get("/api/state", &format!("Cookie: cgnodes_token_1={t}\r\n")).0,
        403
    );
    // DNS rebinding: a foreign name for this address, even with the token.
    let (code, resp) = request(
        p,
        &format!(
            "GET /?token={t} HTTP/1.1\r\nHost: attacker.example:{p}\r\nConnection: close\r\n\r\n"
        ),
    );
    assert_eq!(code, 403, "{resp}");
    assert!(resp.contains("Host"));
    // Another site's page calling in with the user's cookie.
    let (code, resp) = get(
        "/api/state",
        &format!("Origin: http://attacker.example\r\nCookie: cgnodes_token_{p}={t}\r\n"),
    );
    assert_eq!(code, 403, "{resp}");
    // A form post (no JSON content type) cannot set a parameter.
    let body = "node=checker&socket=checker_squares&value=2";
    let (code, _) = request(
        p,
        &format!("POST /api/set?token={t} HTTP/1.1\r\nHost: 127.0.0.1:{p}\r\nContent-Type: application/x-www-form-urlencoded\r\nContent-Length: {}\r\nConnection: close\r\n\r\n{body}", body.len()),
    );
    assert_eq!(code, 415);
    // Files outside --out are not served, however the path is spelled.
    for path in [
        "/files/../tutte.json",
        "/files/%2E%2E/tutte.json",
        "/files//etc/passwd",
    ] {
        let (code, _) = get(&format!("{path}?token={t}"), "");
        assert_ne!(code, 200, "{path}");
    }
    assert!(!std::fs::read_to_string(&g)
        .unwrap()
        .contains("\"checker_squares\": 2"));
}

#[test]
fn serve_page_shows_outputs_reruns_on_a_slider_and_shows_a_broken_edit_on_its_node() {
    if !chromium_available() {
        skip_or_fail(
            "serve_page_shows_outputs_reruns_on_a_slider_and_shows_a_broken_edit_on_its_node",
            "chromium is not installed (apt-get install -y chromium)",
        );
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let g = tutte_graph(dir.path());
    let out = dir.path().join("out");
    let s = serve(&g, &out);
    let mut b = Browser::launch();
    b.open(&s.url).unwrap();
    let long = Duration::from_secs(60);
    // Every node has a card; the run's outputs are on the page and loaded.
    b.wait_for("window.cgnodes && window.cgnodes.shown[1]", long)
        .unwrap();
    let cards = b
        .eval("document.querySelectorAll('section.node').length")
        .unwrap();
    assert_eq!(cards, 9);
    let graph_boxes = b
        .eval("document.querySelectorAll('#graph g.node').length")
        .unwrap();
    assert_eq!(graph_boxes, 9);
    let layout_src = "document.querySelector('#node-save_layout img').src";
    let src1 = b.eval(layout_src).unwrap();
    assert!(src1
        .as_str()
        .unwrap()
        .contains("tutte_cotangent_circle_layout.png?v=1"));
    let loaded = b
        .eval("[...document.querySelectorAll('section.node img')].every(i => i.complete && i.naturalWidth > 0)")
        .unwrap();
    assert_eq!(loaded, true);
    // The metrics table and a mesh viewer (WebGL through SwiftShader) with its mesh.
    assert!(
        b.eval("document.querySelectorAll('#node-save_metrics table tr').length")
            .unwrap()
            .as_u64()
            .unwrap()
            >= 2
    );
    b.wait_for(
        "document.querySelector('#node-save_flat figure.viewer').dataset.loaded",
        long,
    )
    .unwrap();
    let png1 = std::fs::read(out.join("tutte_cotangent_circle_layout.png")).unwrap();

    // Moving the slider writes the file and reruns; the new image appears.
    b.set_widget("checker", "checker_squares", "input[type=range]", "4");
    b.wait_for("window.cgnodes.shown[2]", long).unwrap();
    // The rewritten file has a new URL (its modification time); the run's other files keep
    // theirs.
    let src2 = b.eval(layout_src).unwrap();
    assert_ne!(src2, src1);
    let loaded = b
        .eval("(() => { const i = document.querySelector('#node-save_layout img'); return i.complete && i.naturalWidth; })()")
        .unwrap();
    assert_eq!(loaded, 512);
    let text = std::fs::read_to_string(&g).unwrap();
    assert!(text.contains("\"checker_squares\": 4"), "{text}");
    let png2 = std::fs::read(out.join("tutte_cotangent_circle_layout.png")).unwrap();
    assert_ne!(png1, png2, "the layout image did not change");
    // Only the checkerboard and what it feeds ran again.
    let statuses = b
        .eval("Object.fromEntries([...document.querySelectorAll('section.node')].map(c => [c.dataset.node, c.querySelector('.pill').textContent]))")
        .unwrap();
    assert_eq!(statuses["tutte"], "cached", "{statuses}");
    assert_eq!(statuses["checker"], "ran", "{statuses}");

    // A value out of range is refused next to its widget, and the file is left alone.
    b.set_widget("checker", "checker_size", "input[type=number]", "2");
    let perr = b
        .wait_for(
            "document.querySelector('#node-checker [data-param=checker_size] .perr')?.textContent",
            long,
        )
        .unwrap();
    assert!(
        perr.as_str().unwrap().contains("below the minimum 8"),
        "{perr}"
    );
    assert_eq!(std::fs::read_to_string(&g).unwrap(), text);

    // An editor saves a broken value: the error shows on its node, in the card and the graph.
    std::fs::write(&g, text.replace("\"cotangent\"", "\"cotangentt\"")).unwrap();
    let err = b
        .wait_for(
            "document.querySelector('#node-tutte .err')?.textContent",
            long,
        )
        .unwrap();
    assert!(
        err.as_str().unwrap().contains("'cotangentt' is not one of"),
        "{err}"
    );
    let marked = b
        .eval("[...document.querySelectorAll('#graph g.node')].find(g => g.dataset.node === 'tutte').classList.contains('has-error')")
        .unwrap();
    assert_eq!(marked, true);
    // Invalid JSON: the error on top, the last good page kept.
    std::fs::write(&g, &text[..text.len() / 2]).unwrap();
    let banner = b
        .wait_for(
            "!document.querySelector('#banner').hidden && document.querySelector('#banner').textContent",
            long,
        )
        .unwrap();
    assert!(banner.as_str().unwrap().contains("tutte.json"), "{banner}");
    // Fixed again: everything runs, no error left.
    std::fs::write(&g, &text).unwrap();
    b.wait_for(
        "document.querySelector('#banner').hidden && !document.querySelector('#node-tutte .err') && document.querySelector('#status').textContent.startsWith('ok')",
        long,
    )
    .unwrap();
}

#[test]
fn run_watch_reruns_what_changed_and_survives_a_broken_save() {
    let dir = tempfile::tempdir().unwrap();
    let g = tutte_graph(dir.path());
    let text = std::fs::read_to_string(&g).unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_cgnodes"))
        .arg("run")
        .arg(&g)
        .arg("--out")
        .arg(dir.path().join("out"))
        .args(["--watch", "--no-report"])
        .stderr(Stdio::piped())
        .stdout(Stdio::null())
        .spawn()
        .unwrap();
    let mut lines = BufReader::new(child.stderr.take().unwrap()).lines();
    let mut wait_line = |want: &str| -> Vec<String> {
        let mut seen = Vec::new();
        for l in lines.by_ref() {
            let l = l.unwrap();
            let done = l.contains(want);
            seen.push(l);
            if done {
                return seen;
            }
        }
        panic!("no line with {want:?}; got {seen:?}");
    };
    wait_line("watching");
    std::fs::write(&g, text.replace("\"cotangent\"", "\"bogus\"")).unwrap();
    let broken = wait_line("watching").join("\n");
    assert!(broken.contains("'bogus' is not one of"), "{broken}");
    std::fs::write(
        &g,
        text.replace("\"checker_squares\": 16", "\"checker_squares\": 8"),
    )
    .unwrap();
    let rerun = wait_line("watching").join("\n");
    // The load and Tutte were cached in memory across the runs.
    assert!(rerun.contains("ran 4, cached 5"), "{rerun}");
    let _ = child.kill();
    let _ = child.wait();
}
