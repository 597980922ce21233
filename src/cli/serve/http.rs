//! `serve`'s requests: the checks every request passes (`Gate`: token, `Host`, `Origin`) and
//! the routes.
//!
//! | route | what |
//! |---|---|
//! | `GET /` | the page |
//! | `GET /vendor/NAME` | the vendored viewer (three.js) |
//! | `GET /api/state` | the last run: nodes, statuses, parameters, files (JSON) |
//! | `GET /api/events` | server-sent events: `run`, `log`, `progress`, `done` |
//! | `GET /api/graph` | the graph file's text |
//! | `POST /api/set` | `{"node", "socket", "value"}`: write the value into the graph file, rerun |
//! | `GET /api/mesh?file=REL` | a mesh under `--out` as triangles for the viewer (binary) |
//! | `GET /files/REL` | a file under `--out` |

use super::edit::set_param;
use super::session::{url_decode, Session};
use crate::cli::FileError;
use crate::types::Value;
use serde_json::{json, Value as Json};
use std::io::{Read, Write};
use std::path::{Component, Path, PathBuf};
use std::sync::mpsc::{self, Sender};
use std::time::Duration;
use tiny_http::{Header, Method, Request, Response};

/// The page (HTML, CSS and its script, no external resource).
const PAGE: &str = include_str!("page.html");
/// three.js (npm `three`), vendored with its licence: `vendor/README.md`.
const VENDOR: &[(&str, &str)] = &[
    ("three.module.js", include_str!("vendor/three.module.js")),
    ("three.core.js", include_str!("vendor/three.core.js")),
    ("OrbitControls.js", include_str!("vendor/OrbitControls.js")),
];
/// The largest `POST /api/set` body read.
const MAX_BODY: u64 = 1 << 20;

/// A fresh random token: 128 bits from the OS, as hex.
pub fn new_token() -> String {
    let mut b = [0u8; 16];
    let read = std::fs::File::open("/dev/urandom").and_then(|mut f| f.read_exact(&mut b));
    if read.is_err() {
        // No /dev/urandom: the std hasher's keys come from the OS's randomness too.
        use std::hash::{BuildHasher, Hasher};
        for chunk in b.chunks_mut(8) {
            let mut h = std::collections::hash_map::RandomState::new().build_hasher();
            h.write_u128(
                std::time::SystemTime::now()
                    .elapsed()
                    .map_or(0, |d| d.as_nanos()),
            );
            chunk.copy_from_slice(&h.finish().to_le_bytes());
        }
    }
    b.iter().map(|x| format!("{x:02x}")).collect()
}

/// The checks every request passes.
pub struct Gate {
    token: String,
    /// `Host` values that name this server.
    hosts: Vec<String>,
    /// The cookie carrying the token (per port: cookies are shared between ports).
    cookie: String,
}

/// Why a request was refused.
#[derive(Debug, PartialEq)]
pub enum Refusal {
    /// `Host` is not the served address (DNS rebinding).
    Host,
    /// `Origin` is another site.
    Origin,
    /// No token, or a wrong one.
    Token,
}

impl Gate {
    /// The gate of a server listening on `host:port` with `token`.
    pub fn new(host: &str, port: u16, token: String) -> Gate {
        let mut hosts: Vec<String> = ["127.0.0.1", "localhost", "[::1]"]
            .iter()
            .map(|h| format!("{h}:{port}"))
            .collect();
        let h = if host.contains(':') && !host.starts_with('[') {
            format!("[{host}]")
        } else {
            host.to_string()
        };
        hosts.push(format!("{h}:{port}"));
        Gate {
            token,
            hosts,
            cookie: format!("cgnodes_token_{port}"),
        }
    }

    /// Checks `Host`, `Origin` and the token (the `token` query parameter or the cookie).
    pub fn check(
        &self,
        host: Option<&str>,
        origin: Option<&str>,
        query_token: Option<&str>,
        cookie: Option<&str>,
    ) -> Result<(), Refusal> {
        if !host.is_some_and(|h| self.hosts.iter().any(|x| x.eq_ignore_ascii_case(h))) {
            return Err(Refusal::Host);
        }
        if let Some(o) = origin {
            let ok = o
                .strip_prefix("http://")
                .is_some_and(|h| self.hosts.iter().any(|x| x.eq_ignore_ascii_case(h)));
            if !ok {
                return Err(Refusal::Origin);
            }
        }
        let from_cookie = cookie.and_then(|c| {
            c.split(';').find_map(|kv| {
                let (k, v) = kv.trim().split_once('=')?;
                (k == self.cookie).then_some(v)
            })
        });
        let given = query_token.or(from_cookie).unwrap_or("");
        if !same(given.as_bytes(), self.token.as_bytes()) {
            return Err(Refusal::Token);
        }
        Ok(())
    }
}

/// Compares in time independent of where the inputs differ.
fn same(a: &[u8], b: &[u8]) -> bool {
    a.len() == b.len() && a.iter().zip(b).fold(0u8, |acc, (x, y)| acc | (x ^ y)) == 0
}

fn header<'a>(req: &'a Request, name: &str) -> Option<&'a str> {
    req.headers()
        .iter()
        .find(|h| h.field.as_str().as_str().eq_ignore_ascii_case(name))
        .map(|h| h.value.as_str())
}

fn hdr(k: &str, v: &str) -> Header {
    Header::from_bytes(k.as_bytes(), v.as_bytes()).unwrap_or_else(|_| {
        Header::from_bytes(&b"X-Invalid"[..], &b"1"[..]).expect("a valid header")
    })
}

/// The query parameter `key` of `url`, decoded.
fn query(url: &str, key: &str) -> Option<String> {
    let q = url.split_once('?')?.1;
    q.split('&').find_map(|kv| {
        let (k, v) = kv.split_once('=').unwrap_or((kv, ""));
        (k == key).then(|| url_decode(v)).flatten()
    })
}

type Resp = Response<std::io::Cursor<Vec<u8>>>;

fn text(code: u16, ctype: &str, body: impl Into<Vec<u8>>) -> Resp {
    cached(code, ctype, body, "no-store")
}

/// A response with its own `Cache-Control`.
fn cached(code: u16, ctype: &str, body: impl Into<Vec<u8>>, cache: &str) -> Resp {
    Response::from_data(body.into())
        .with_status_code(code)
        .with_header(hdr("Content-Type", ctype))
        .with_header(hdr("Cache-Control", cache))
        .with_header(hdr("X-Content-Type-Options", "nosniff"))
}

/// The page's URLs of files and meshes carry the file's modification time, so what a URL
/// names never changes: the browser may keep it.
const KEEP: &str = "private, max-age=86400";

fn error(code: u16, message: &str) -> Resp {
    text(
        code,
        "application/json",
        json!({ "error": message }).to_string(),
    )
}

/// Answers one request.
pub fn handle(mut req: Request, session: &Session, gate: &Gate, run: &Sender<()>) {
    let url = req.url().to_string();
    let path = url.split('?').next().unwrap_or("").to_string();
    let qtoken = query(&url, "token");
    let checked = gate.check(
        header(&req, "Host"),
        header(&req, "Origin"),
        qtoken.as_deref(),
        header(&req, "Cookie"),
    );
    if let Err(r) = checked {
        let msg = match r {
            Refusal::Host => "refused: the Host header is not this server's address",
            Refusal::Origin => "refused: the request comes from another site",
            Refusal::Token => "refused: the token is missing or wrong (use the URL serve printed)",
        };
        let _ = req.respond(error(403, msg));
        return;
    }
    let method = req.method().clone();
    let resp = match (method, path.as_str()) {
        (Method::Get, "/") => {
            let mut r = text(200, "text/html; charset=utf-8", PAGE)
                .with_header(hdr("Content-Security-Policy", "default-src 'self'; script-src 'self' 'unsafe-inline'; style-src 'unsafe-inline'; img-src 'self' data:; connect-src 'self'"));
            if let Some(t) = qtoken {
                r = r.with_header(hdr(
                    "Set-Cookie",
                    &format!("{}={t}; HttpOnly; SameSite=Strict; Path=/", gate.cookie),
                ));
            }
            r
        }
        (Method::Get, "/api/state") => text(200, "application/json", session.state_json()),
        (Method::Get, "/api/graph") => text(200, "application/json", session.text()),
        (Method::Get, "/api/events") => {
            events(req, session);
            return;
        }
        (Method::Post, "/api/set") => set(&mut req, session, run),
        (Method::Get, "/api/mesh") => mesh(&url, session),
        (Method::Get, p) if p.starts_with("/vendor/") => {
            let name = &p["/vendor/".len()..];
            match VENDOR.iter().find(|(n, _)| *n == name) {
                Some((_, body)) => cached(200, "text/javascript; charset=utf-8", *body, KEEP),
                None => error(404, "no such file"),
            }
        }
        (Method::Get, p) if p.starts_with("/files/") => {
            match out_file(session, &p["/files/".len()..]) {
                Ok(f) => match std::fs::read(&f) {
                    Ok(bytes) => cached(200, content_type(&f), bytes, KEEP),
                    Err(e) => error(404, &format!("{}: {e}", f.display())),
                },
                Err(e) => error(403, &e.to_string()),
            }
        }
        _ => error(404, "no such route"),
    };
    let _ = req.respond(resp);
}

/// `POST /api/set`: checks the value against the socket's declaration, writes it into the
/// graph file's text, and asks for a run.
fn set(req: &mut Request, session: &Session, run: &Sender<()>) -> Resp {
    if !header(req, "Content-Type").is_some_and(|c| c.starts_with("application/json")) {
        // A cross-site form cannot send JSON without a preflight the server never answers.
        return error(415, "send JSON (Content-Type: application/json)");
    }
    let mut body = String::new();
    if req
        .as_reader()
        .take(MAX_BODY)
        .read_to_string(&mut body)
        .is_err()
    {
        return error(400, "unreadable body");
    }
    let Ok(j) = serde_json::from_str::<Json>(&body) else {
        return error(400, "the body is not JSON");
    };
    let (Some(node), Some(socket), Some(value)) =
        (j["node"].as_str(), j["socket"].as_str(), j.get("value"))
    else {
        return error(400, "expected {\"node\", \"socket\", \"value\"}");
    };
    match session.set_param(node, socket, value) {
        Ok(()) => {
            let _ = run.send(());
            text(200, "application/json", json!({ "ok": true }).to_string())
        }
        Err(e) => error(400, &e.to_string()),
    }
}

/// `GET /api/events`: the head written by hand, then each event flushed as it comes (the
/// server's chunked writer would hold small events back).
fn events(req: Request, session: &Session) {
    let (tx, rx) = mpsc::channel::<String>();
    session.subscribe(tx);
    let mut w = req.into_writer();
    let head = "HTTP/1.1 200 OK\r\nContent-Type: text/event-stream\r\nCache-Control: no-store\r\nConnection: close\r\n\r\n: connected\n\n";
    if w.write_all(head.as_bytes())
        .and_then(|_| w.flush())
        .is_err()
    {
        return;
    }
    loop {
        let msg = match rx.recv_timeout(Duration::from_secs(15)) {
            Ok(m) => m,
            // A comment now and then finds pages that went away.
            Err(mpsc::RecvTimeoutError::Timeout) => ": ping\n\n".to_string(),
            Err(mpsc::RecvTimeoutError::Disconnected) => return,
        };
        if w.write_all(msg.as_bytes()).and_then(|_| w.flush()).is_err() {
            return;
        }
    }
}

/// `GET /api/mesh?file=REL`: little-endian u32 vertex count, u32 triangle count, u32 flags
/// (1: texture coordinates follow the positions), f32 positions, f32 UVs, u32 indices.
/// Faces are fanned into triangles; with per-corner UVs each triangle gets its own corners.
fn mesh(url: &str, session: &Session) -> Resp {
    let Some(rel) = query(url, "file") else {
        return error(400, "expected ?file=");
    };
    let f = match out_file(session, &rel) {
        Ok(f) => f,
        Err(e) => return error(403, &e.to_string()),
    };
    match cgnodes_formats::mesh_file::load_mesh(&f, &Default::default()) {
        Ok(m) => cached(200, "application/octet-stream", viewer_mesh(&m), KEEP),
        Err(e) => error(422, &e.to_string()),
    }
}

/// A mesh in `/api/mesh`'s layout.
fn viewer_mesh(m: &crate::types::Mesh) -> Vec<u8> {
    use crate::types::Domain;
    let starts = m.face_starts();
    // (vertex, corner) of each triangle corner.
    let corners: Vec<(u32, u32)> = m
        .faces()
        .enumerate()
        .flat_map(|(fi, f)| {
            let s = starts[fi];
            (1..f.len().saturating_sub(1)).flat_map(move |i| {
                [
                    (f[0], s),
                    (f[i], s + i as u32),
                    (f[i + 1], s + i as u32 + 1),
                ]
            })
        })
        .collect();
    let uvs = m.uvs.as_ref();
    let per_corner = uvs.is_some_and(|u| u.domain == Domain::Corner);
    let with_uv = uvs.is_some_and(|u| u.domain != Domain::Face);
    let (positions, uv, indices): (Vec<[f64; 3]>, Vec<[f64; 2]>, Vec<u32>) = if per_corner {
        let u = &uvs.expect("checked").values;
        (
            corners
                .iter()
                .map(|&(v, _)| m.positions[v as usize])
                .collect(),
            corners
                .iter()
                .map(|&(_, c)| u.get(c as usize).copied().unwrap_or_default())
                .collect(),
            (0..corners.len() as u32).collect(),
        )
    } else {
        let uv = match uvs {
            Some(u) if with_uv => u.values.clone(),
            _ => Vec::new(),
        };
        (
            m.positions.clone(),
            uv,
            corners.iter().map(|&(v, _)| v).collect(),
        )
    };
    let mut out = Vec::new();
    out.extend((positions.len() as u32).to_le_bytes());
    out.extend(((indices.len() / 3) as u32).to_le_bytes());
    out.extend(u32::from(with_uv).to_le_bytes());
    for c in positions.iter().flatten() {
        out.extend((*c as f32).to_le_bytes());
    }
    if with_uv {
        for i in 0..positions.len() {
            for c in uv.get(i).copied().unwrap_or_default() {
                out.extend((c as f32).to_le_bytes());
            }
        }
    }
    for i in &indices {
        out.extend(i.to_le_bytes());
    }
    out
}

/// The file `rel` (URL-encoded, relative) under `--out`: no `..`, no absolute path, and after
/// resolving links still inside `--out`.
fn out_file(session: &Session, rel: &str) -> Result<PathBuf, OutFileError> {
    let rel = url_decode(rel).ok_or(OutFileError::BadEscape)?;
    let p = Path::new(&rel);
    if p.components().any(|c| !matches!(c, Component::Normal(_))) {
        return Err(OutFileError::NotPlain);
    }
    let out = session
        .setup
        .out
        .canonicalize()
        .map_err(FileError::at(&session.setup.out))?;
    let f = out
        .join(p)
        .canonicalize()
        .map_err(|_| OutFileError::NotFound(rel.clone()))?;
    if !f.starts_with(&out) {
        return Err(OutFileError::Outside);
    }
    Ok(f)
}

/// Why a `/files/` or `/api/mesh` path names no file the page may read (a 403).
#[derive(Debug, thiserror::Error)]
enum OutFileError {
    /// A `%` escape that does not decode.
    #[error("bad escape in the path")]
    BadEscape,
    /// `..`, a root or a prefix in the path.
    #[error("only plain paths under the output folder")]
    NotPlain,
    /// The output folder itself is gone.
    #[error(transparent)]
    Out(#[from] FileError),
    /// No such file.
    #[error("{0}: not found")]
    NotFound(String),
    /// A link that leads out of the output folder.
    #[error("only files under the output folder")]
    Outside,
}

/// Why the page's parameter edit was refused (a 400).
#[derive(Debug, thiserror::Error)]
pub enum SetParamError {
    /// The graph file could not be read, parsed or written.
    #[error(transparent)]
    File(#[from] FileError),
    /// The node is not in the graph file.
    #[error("no node '{0}' in the graph file")]
    NoNode(String),
    /// The node's type is not registered.
    #[error("node '{node}': unknown node type '{ty}'")]
    UnknownType {
        /// The node id.
        node: String,
        /// Its type.
        ty: String,
    },
    /// The node type has no such input.
    #[error("node '{node}' ({ty}): no input '{socket}'")]
    NoInput {
        /// The node id.
        node: String,
        /// Its type.
        ty: String,
        /// The socket.
        socket: String,
    },
    /// The input is linked: a literal cannot replace the link.
    #[error("node '{node}' ({ty}): input '{socket}' is linked")]
    Linked {
        /// The node id.
        node: String,
        /// Its type.
        ty: String,
        /// The socket.
        socket: String,
    },
    /// The value is not a valid literal of the socket (the literal check's message).
    #[error("node '{node}' ({ty}): input '{socket}': {message}")]
    BadValue {
        /// The node id.
        node: String,
        /// Its type.
        ty: String,
        /// The socket.
        socket: String,
        /// Why the value does not fit.
        message: String,
    },
    /// The graph file's text could not be edited in place.
    #[error("{0}")]
    Edit(#[from] super::edit::EditError),
}

fn content_type(p: &Path) -> &'static str {
    match p
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase()
        .as_str()
    {
        "png" => "image/png",
        "jpg" | "jpeg" => "image/jpeg",
        "gif" => "image/gif",
        "bmp" => "image/bmp",
        "webp" => "image/webp",
        "svg" => "image/svg+xml",
        "csv" | "obj" | "mtl" | "usda" | "off" | "txt" => "text/plain; charset=utf-8",
        "json" => "application/json",
        _ => "application/octet-stream",
    }
}

impl Session<'_> {
    /// Sets `node.socket` to `value` in the graph file after checking it against the socket's
    /// declaration; the file is replaced atomically and only the value's bytes change.
    pub fn set_param(&self, node: &str, socket: &str, value: &Json) -> Result<(), SetParamError> {
        let path = &self.setup.graph;
        let text = std::fs::read_to_string(path).map_err(FileError::at(path))?;
        let spec: Json = serde_json::from_str(&text).map_err(FileError::at(path))?;
        let ty = spec["nodes"][node]["type"]
            .as_str()
            .ok_or_else(|| SetParamError::NoNode(node.into()))?;
        let decl = self
            .registry()
            .get(ty)
            .ok_or_else(|| SetParamError::UnknownType {
                node: node.into(),
                ty: ty.into(),
            })?;
        let s = decl.input(socket).ok_or_else(|| SetParamError::NoInput {
            node: node.into(),
            ty: ty.into(),
            socket: socket.into(),
        })?;
        if spec["nodes"][node]["inputs"].get(socket).is_some() {
            return Err(SetParamError::Linked {
                node: node.into(),
                ty: ty.into(),
                socket: socket.into(),
            });
        }
        let bad_value = |message: String| SetParamError::BadValue {
            node: node.into(),
            ty: ty.into(),
            socket: socket.into(),
            message,
        };
        let v = Value::from_json(&s.ty, value).map_err(bad_value)?;
        s.check_literal(&v).map_err(bad_value)?;
        let new = set_param(&text, node, socket, value)?;
        self.note_written(&new);
        crate::io::write_atomic(path, |w| w.write_all(new.as_bytes()))
            .map_err(FileError::at(path))?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_gate_wants_the_served_host_a_same_site_origin_and_the_token() {
        let g = Gate::new("127.0.0.1", 8000, "abc".into());
        let host = Some("127.0.0.1:8000");
        assert_eq!(g.check(host, None, Some("abc"), None), Ok(()));
        assert_eq!(
            g.check(Some("localhost:8000"), None, Some("abc"), None),
            Ok(())
        );
        assert_eq!(
            g.check(host, None, None, Some("a=1; cgnodes_token_8000=abc")),
            Ok(())
        );
        assert_eq!(
            g.check(host, None, None, Some("cgnodes_token_9000=abc")),
            Err(Refusal::Token)
        );
        assert_eq!(g.check(host, None, Some("abd"), None), Err(Refusal::Token));
        assert_eq!(g.check(host, None, None, None), Err(Refusal::Token));
        assert_eq!(
            g.check(Some("evil.example:8000"), None, Some("abc"), None),
            Err(Refusal::Host)
        );
        assert_eq!(g.check(None, None, Some("abc"), None), Err(Refusal::Host));
        assert_eq!(
            g.check(host, Some("http://evil.example"), Some("abc"), None),
            Err(Refusal::Origin)
        );
        assert_eq!(
            g.check(host, Some("http://127.0.0.1:8000"), Some("abc"), None),
            Ok(())
        );
    }

    #[test]
    fn meshes_reach_the_viewer_as_triangles_with_their_uvs() {
        use crate::types::{Attribute, Domain, Mesh};
        let u32s = |b: &[u8], at: usize| u32::from_le_bytes(b[at..at + 4].try_into().unwrap());
        let f32s = |b: &[u8], at: usize| f32::from_le_bytes(b[at..at + 4].try_into().unwrap());
        let p = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ];
        // A quad: fanned into two triangles over the same four vertices.
        let mut quad = Mesh::new(p.clone(), vec![4], vec![0, 1, 2, 3]).unwrap();
        let b = viewer_mesh(&quad);
        assert_eq!((u32s(&b, 0), u32s(&b, 4), u32s(&b, 8)), (4, 2, 0));
        let idx: Vec<u32> = (0..6).map(|i| u32s(&b, 12 + 48 + 4 * i)).collect();
        assert_eq!(idx, [0, 1, 2, 0, 2, 3]);
        assert_eq!(f32s(&b, 12 + 3 * 4 * 2 + 4), 1.0); // y of vertex 2
                                                       // Per-corner UVs: each triangle corner is its own vertex, with its corner's UV.
        quad.uvs = Some(Attribute {
            domain: Domain::Corner,
            values: vec![[0.0, 0.0], [0.5, 0.0], [0.5, 0.5], [0.0, 0.5]],
        });
        let b = viewer_mesh(&quad);
        assert_eq!((u32s(&b, 0), u32s(&b, 4), u32s(&b, 8)), (6, 2, 1));
        let uv_at = 12 + 6 * 12;
        // Corner 4 of the soup is the second triangle's second corner: the quad's corner 2.
        assert_eq!(
            (f32s(&b, uv_at + 4 * 8), f32s(&b, uv_at + 4 * 8 + 4)),
            (0.5, 0.5)
        );
    }

    #[test]
    fn tokens_are_random_hex() {
        let (a, b) = (new_token(), new_token());
        assert_eq!(a.len(), 32);
        assert!(a.bytes().all(|c| c.is_ascii_hexdigit()));
        assert_ne!(a, b);
    }
}
