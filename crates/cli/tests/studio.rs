//! The studio: its HTTP safety rules, and the whole page in a real browser (Debian's chromium
//! driven by playwright-core, `tools/studio-e2e.mjs`) on the ICT head: draw a stroke, drag the
//! arrow, undo/redo, symmetry, save and reopen, a broken upload. Screenshots go to
//! `test-output/studio/`.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    reason = "tests"
)]

mod support;

use std::io::{BufRead as _, BufReader, Read as _, Write as _};
use std::net::TcpStream;
use std::process::{Child, Command, Stdio};

use support::{output_dir, repo};

/// A running studio, stopped when dropped.
struct Studio {
    child: Child,
    port: u16,
}

impl Drop for Studio {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn start(project: &std::path::Path) -> Studio {
    let mut child = Command::new(env!("CARGO_BIN_EXE_faceanim"))
        .args([
            "studio",
            faceanim_testdata::shared("characters/ict-face.glb")
                .to_str()
                .unwrap(),
            "--port",
            "0",
            "--project",
        ])
        .arg(project)
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .unwrap();
    let mut line = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut line)
        .unwrap();
    // "faceanim studio: http://127.0.0.1:PORT/  (…)"
    let port = line
        .split("127.0.0.1:")
        .nth(1)
        .and_then(|rest| rest.split('/').next())
        .and_then(|p| p.parse().ok())
        .unwrap_or_else(|| panic!("no URL in the studio's first line: {line}"));
    Studio { child, port }
}

/// One raw HTTP/1.1 request; returns the status code and body.
fn request(
    port: u16,
    method: &str,
    path: &str,
    headers: &[(&str, &str)],
    body: &[u8],
) -> (u16, String) {
    let mut stream = TcpStream::connect(("127.0.0.1", port)).unwrap();
    let mut text = format!(
        "{method} {path} HTTP/1.1\r\nConnection: close\r\nContent-Length: {}\r\n",
        body.len()
    );
    if !headers.iter().any(|(k, _)| k.eq_ignore_ascii_case("host")) {
        text.push_str(&format!("Host: 127.0.0.1:{port}\r\n"));
    }
    for (k, v) in headers {
        text.push_str(&format!("{k}: {v}\r\n"));
    }
    text.push_str("\r\n");
    stream.write_all(text.as_bytes()).unwrap();
    stream.write_all(body).unwrap();
    let mut response = Vec::new();
    stream.read_to_end(&mut response).unwrap();
    let response = String::from_utf8_lossy(&response).into_owned();
    let status = response
        .split(' ')
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap();
    let body = response.split("\r\n\r\n").nth(1).unwrap_or("").to_owned();
    (status, body)
}

#[test]
fn only_its_own_host_and_origin_are_served() {
    let dir = tempfile::tempdir().unwrap();
    let studio = start(&dir.path().join("p.json"));
    let port = studio.port;
    assert_eq!(request(port, "GET", "/api/state", &[], b"").0, 200);
    let own = format!("localhost:{port}");
    assert_eq!(
        request(port, "GET", "/api/state", &[("Host", &own)], b"").0,
        200
    );
    // DNS rebinding: a page on another name resolving to 127.0.0.1.
    let (status, body) = request(
        port,
        "GET",
        "/api/state",
        &[("Host", "attacker.example:80")],
        b"",
    );
    assert_eq!(status, 403, "{body}");
    // Another site's page posting to the studio.
    let (status, _) = request(
        port,
        "POST",
        "/api/undo",
        &[("Origin", "http://attacker.example")],
        b"",
    );
    assert_eq!(status, 403);
    let origin = format!("http://127.0.0.1:{port}");
    assert_eq!(
        request(port, "POST", "/api/undo", &[("Origin", &origin)], b"").0,
        200
    );
    // The page is embedded: paths outside it do not reach the file system.
    assert_eq!(request(port, "GET", "/../../Cargo.toml", &[], b"").0, 404);
    assert_eq!(
        request(port, "GET", "/%2e%2e/%2e%2e/Cargo.toml", &[], b"").0,
        404
    );
    // Bad JSON gets a message naming what was wrong.
    let (status, body) = request(
        port,
        "POST",
        "/api/strokes",
        &[("Content-Type", "application/json")],
        b"{\"samples\": 3}",
    );
    assert_eq!(status, 400);
    assert!(body.contains("stroke"), "{body}");
    // Oversized JSON is refused before it is read.
    let big = vec![b' '; 17 * 1024 * 1024];
    assert_eq!(request(port, "PUT", "/api/project", &[], &big).0, 413);
}

#[test]
fn an_animator_session_in_a_real_browser() {
    let dir = tempfile::tempdir().unwrap();
    let studio = start(&dir.path().join("session.faceanim.json"));
    let out = output_dir("studio");
    let script = repo().join("tools/studio-e2e.mjs");
    assert!(
        repo().join("tools/node_modules/playwright-core").exists(),
        "playwright-core is not installed: run scripts/setup.sh"
    );
    let run = Command::new("node")
        .arg(&script)
        .arg(format!("http://127.0.0.1:{}/", studio.port))
        .arg(&out)
        .output()
        .expect("node");
    let stdout = String::from_utf8_lossy(&run.stdout);
    eprintln!("{stdout}");
    assert!(
        run.status.success(),
        "{}\n{}",
        stdout,
        String::from_utf8_lossy(&run.stderr)
    );
    let measured: serde_json::Value = serde_json::from_str(stdout.lines().last().unwrap()).unwrap();
    assert!(measured["smile_weight"].as_f64().unwrap() > 0.5);
    // The project was saved where the studio was pointed, and nowhere else.
    assert!(dir.path().join("session.faceanim.json").exists());
}
