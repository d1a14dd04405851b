//! `hce serve FILE`: the browser viewer (`web/viewer.html`, issue 17) for one baked file, served
//! on 127.0.0.1 only. The page, its modules and the runtime's WGSL kernels are embedded in the
//! binary, byte for byte the files of `web/` and `runtime/src/gpu/` at build time (the page
//! assembles the kernels from the latter as `runtime/src/gpu/wgsl.rs` does), so the command
//! works offline from any directory. It prints the URL and serves until interrupted.
//!
//! The server is deliberately small: `std::net`, one request per connection
//! (`Connection: close`), GET and HEAD only, request heads bounded in size and time, and only
//! the embedded files and the asset (for a `.gltf`, also the files beside it that it names by
//! relative URI) are reachable.

use std::io::{BufRead, BufReader, Read, Write};
use std::net::{Ipv4Addr, TcpListener, TcpStream};
use std::path::{Component, Path, PathBuf};
use std::time::Duration;

use anyhow::{bail, Context, Result};
use clap::Args;
use hce_meshio::gltf_guard::percent_encode;

#[derive(Args, Debug)]
pub struct ServeArgs {
    /// A baked `.glb`, `.gltf` or `.hce` file.
    pub file: PathBuf,
    /// Port on 127.0.0.1 (0: any free port).
    #[arg(long, default_value_t = 0)]
    pub port: u16,
    /// Stop after this many requests (for tests and scripts); default: serve until interrupted.
    #[arg(long)]
    pub max_requests: Option<u64>,
}

/// One embedded file: its URL path and bytes.
type Embedded = (&'static str, &'static [u8]);

macro_rules! embed {
    ($($url:literal => $path:literal),* $(,)?) => {
        &[$(($url, include_bytes!(concat!(env!("CARGO_MANIFEST_DIR"), "/../", $path)))),*]
    };
}

/// The page, its modules and the kernels' WGSL, at the paths they have in the repository (the
/// page finds the WGSL at `../runtime/src/gpu/`). `tests` below checks that every file of
/// `web/src/` and every `.wgsl` of `runtime/src/gpu/` is here.
const EMBEDDED: &[Embedded] = embed! {
    "/web/viewer.html" => "web/viewer.html",
    "/web/src/cpu_refine.js" => "web/src/cpu_refine.js",
    "/web/src/device.js" => "web/src/device.js",
    "/web/src/errors.js" => "web/src/errors.js",
    "/web/src/index.js" => "web/src/index.js",
    "/web/src/kernels.js" => "web/src/kernels.js",
    "/web/src/math.js" => "web/src/math.js",
    "/web/src/native.js" => "web/src/native.js",
    "/web/src/pipelines.js" => "web/src/pipelines.js",
    "/web/src/present.wgsl" => "web/src/present.wgsl",
    "/web/src/scene.js" => "web/src/scene.js",
    "/web/src/view.js" => "web/src/view.js",
    "/web/src/viewer.js" => "web/src/viewer.js",
    "/web/src/webgl_scene.js" => "web/src/webgl_scene.js",
    "/web/src/wgsl.js" => "web/src/wgsl.js",
    "/web/src/three/HceGLTFPlugin.js" => "web/src/three/HceGLTFPlugin.js",
    "/web/src/three/gpu_geometry.js" => "web/src/three/gpu_geometry.js",
    "/runtime/src/gpu/decode.wgsl" => "runtime/src/gpu/decode.wgsl",
    "/runtime/src/gpu/fill.wgsl" => "runtime/src/gpu/fill.wgsl",
    "/runtime/src/gpu/flat.wgsl" => "runtime/src/gpu/flat.wgsl",
    "/runtime/src/gpu/hce_batch.wgsl" => "runtime/src/gpu/hce_batch.wgsl",
    "/runtime/src/gpu/hce_bindings.wgsl" => "runtime/src/gpu/hce_bindings.wgsl",
    "/runtime/src/gpu/hce_constants.wgsl" => "runtime/src/gpu/hce_constants.wgsl",
    "/runtime/src/gpu/hce_gather.wgsl" => "runtime/src/gpu/hce_gather.wgsl",
    "/runtime/src/gpu/hce_lattice.wgsl" => "runtime/src/gpu/hce_lattice.wgsl",
    "/runtime/src/gpu/hce_light.wgsl" => "runtime/src/gpu/hce_light.wgsl",
    "/runtime/src/gpu/hce_tree.wgsl" => "runtime/src/gpu/hce_tree.wgsl",
    "/runtime/src/gpu/loop.wgsl" => "runtime/src/gpu/loop.wgsl",
    "/runtime/src/gpu/loop_batch.wgsl" => "runtime/src/gpu/loop_batch.wgsl",
    "/runtime/src/gpu/loop_normals.wgsl" => "runtime/src/gpu/loop_normals.wgsl",
    "/runtime/src/gpu/loop_workgroup.wgsl" => "runtime/src/gpu/loop_workgroup.wgsl",
    "/runtime/src/gpu/render.wgsl" => "runtime/src/gpu/render.wgsl",
    "/runtime/src/gpu/render_resolve.wgsl" => "runtime/src/gpu/render_resolve.wgsl",
};

/// Where the page's `hce.wasm` is served from. It is a build output (`web/build-wasm.sh`), not a
/// source file, so it cannot be embedded at compile time: `HCE_WASM` names it, else an
/// `hce.wasm` beside the executable, else the one the script writes in this source tree.
fn wasm_path() -> Option<PathBuf> {
    let candidates = [
        std::env::var_os("HCE_WASM").map(PathBuf::from),
        std::env::current_exe()
            .ok()
            .and_then(|e| e.parent().map(|d| d.join("hce.wasm"))),
        Some(Path::new(env!("CARGO_MANIFEST_DIR")).join("../web/src/hce.wasm")),
    ];
    candidates.into_iter().flatten().find(|p| p.is_file())
}

const WASM_URL: &str = "/web/src/hce.wasm";
const WASM_MISSING: &str =
    "hce.wasm not found: build it with web/build-wasm.sh and name it in HCE_WASM (or put it beside the hce executable)";

/// The longest request head read before the request is refused.
const MAX_HEAD: u64 = 16 * 1024;
/// How long a client may take to send its request or read the answer.
const IO_TIMEOUT: Duration = Duration::from_secs(10);

/// What a request is answered with.
#[derive(Debug, PartialEq)]
enum Reply {
    Embedded(&'static [u8], &'static str),
    File(PathBuf, &'static str),
    Redirect(String),
    Status(u16, &'static str),
}

fn content_type(path: &str) -> &'static str {
    match path.rsplit('.').next().unwrap_or("") {
        "html" => "text/html; charset=utf-8",
        "js" => "text/javascript; charset=utf-8",
        "wgsl" => "text/plain; charset=utf-8",
        "gltf" => "model/gltf+json",
        "glb" => "model/gltf-binary",
        // WebAssembly.instantiateStreaming insists on this type.
        "wasm" => "application/wasm",
        _ => "application/octet-stream",
    }
}

/// The asset as the page asks for it: `/file/NAME`, and for a `.gltf` the relative files it
/// names (`/file/DIR/x.bin`), never outside the asset's directory.
struct Asset {
    dir: PathBuf,
    name: String,
    gltf: bool,
}

impl Asset {
    fn url(&self) -> String {
        format!("/file/{}", percent_encode(&self.name))
    }
}

/// Decodes `%XX` escapes; `None` for a malformed escape or bytes that are not UTF-8.
fn percent_decode(s: &str) -> Option<String> {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' {
            let hex = std::str::from_utf8(b.get(i + 1..i + 3)?).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

/// Routes a request target (path and query) to its reply.
fn route(target: &str, asset: &Asset) -> Reply {
    let path = target.split(['?', '#']).next().unwrap_or("");
    if path == "/" {
        return Reply::Redirect(format!("/web/viewer.html?url={}", asset.url()));
    }
    if let Some(&(url, bytes)) = EMBEDDED.iter().find(|(url, _)| *url == path) {
        return Reply::Embedded(bytes, content_type(url));
    }
    if path == WASM_URL {
        return match wasm_path() {
            Some(p) => Reply::File(p, content_type(WASM_URL)),
            None => Reply::Status(404, WASM_MISSING),
        };
    }
    let Some(rest) = path.strip_prefix("/file/") else {
        return Reply::Status(404, "not found");
    };
    let Some(rel) = percent_decode(rest) else {
        return Reply::Status(400, "bad path");
    };
    let rel = Path::new(&rel);
    // Plain relative names only: no root, no `..`, no `.`.
    if rel.components().any(|c| !matches!(c, Component::Normal(_))) {
        return Reply::Status(404, "not found");
    }
    let is_asset = rel == Path::new(&asset.name);
    if !is_asset && !asset.gltf {
        return Reply::Status(404, "not found");
    }
    Reply::File(asset.dir.join(rel), content_type(&rel.to_string_lossy()))
}

/// Reads the request line (bounded), then the rest of the head, and returns the method and target.
fn read_request(stream: &TcpStream) -> Option<(String, String)> {
    let mut reader = BufReader::new(stream.take(MAX_HEAD));
    let mut line = String::new();
    reader.read_line(&mut line).ok()?;
    let mut parts = line.split_whitespace();
    let method = parts.next()?.to_string();
    let target = parts.next()?.to_string();
    // Drain the headers so the client sees its request read; stop at the blank line.
    let mut header = String::new();
    while reader.read_line(&mut header).ok()? > 2 {
        header.clear();
    }
    Some((method, target))
}

/// A response before it is written.
struct Response<'a> {
    code: u16,
    kind: &'a str,
    body: std::borrow::Cow<'a, [u8]>,
    location: Option<String>,
}

impl<'a> Response<'a> {
    fn new(code: u16, kind: &'a str, body: impl Into<std::borrow::Cow<'a, [u8]>>) -> Self {
        Self {
            code,
            kind,
            body: body.into(),
            location: None,
        }
    }

    fn text(code: u16, text: &'a str) -> Self {
        Self::new(code, "text/plain; charset=utf-8", text.as_bytes())
    }
}

fn respond(mut stream: TcpStream, asset: &Asset) -> std::io::Result<()> {
    stream.set_read_timeout(Some(IO_TIMEOUT))?;
    stream.set_write_timeout(Some(IO_TIMEOUT))?;
    let Some((method, target)) = read_request(&stream) else {
        return write_response(&mut stream, &Response::text(400, "bad request"), false);
    };
    let head_only = method == "HEAD";
    if method != "GET" && !head_only {
        return write_response(&mut stream, &Response::text(405, "GET or HEAD only"), false);
    }
    let response = match route(&target, asset) {
        Reply::Embedded(bytes, kind) => Response::new(200, kind, bytes),
        Reply::File(path, kind) => match std::fs::read(&path) {
            Ok(bytes) => Response::new(200, kind, bytes),
            Err(_) => Response::text(404, "not found"),
        },
        Reply::Redirect(to) => Response {
            location: Some(to),
            ..Response::text(302, "")
        },
        Reply::Status(code, text) => Response::text(code, text),
    };
    write_response(&mut stream, &response, head_only)
}

fn write_response(stream: &mut TcpStream, r: &Response, head_only: bool) -> std::io::Result<()> {
    let reason = match r.code {
        200 => "OK",
        302 => "Found",
        400 => "Bad Request",
        404 => "Not Found",
        405 => "Method Not Allowed",
        _ => "Error",
    };
    let mut head = format!(
        "HTTP/1.1 {} {reason}\r\nContent-Type: {}\r\nContent-Length: {}\r\n\
         Cache-Control: no-store\r\nConnection: close\r\n",
        r.code,
        r.kind,
        r.body.len()
    );
    if let Some(to) = &r.location {
        head.push_str(&format!("Location: {to}\r\n"));
    }
    head.push_str("\r\n");
    stream.write_all(head.as_bytes())?;
    if !head_only {
        stream.write_all(&r.body)?;
    }
    stream.flush()
}

pub fn run(args: ServeArgs) -> Result<()> {
    let file = &args.file;
    let meta = std::fs::metadata(file).with_context(|| format!("{}", file.display()))?;
    if !meta.is_file() {
        bail!("{} is not a file", file.display());
    }
    let name = file
        .file_name()
        .and_then(|n| n.to_str())
        .with_context(|| format!("{}: the file name is not UTF-8", file.display()))?
        .to_string();
    let dir = file
        .parent()
        .map(Path::to_path_buf)
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or_else(|| PathBuf::from("."));
    let gltf = name.to_ascii_lowercase().ends_with(".gltf");
    let asset = Asset { dir, name, gltf };
    let listener = TcpListener::bind((Ipv4Addr::LOCALHOST, args.port))
        .with_context(|| format!("cannot listen on 127.0.0.1:{}", args.port))?;
    let port = listener.local_addr()?.port();
    println!(
        "hce viewer for {}: http://127.0.0.1:{port}/web/viewer.html?url={}",
        file.display(),
        asset.url()
    );
    println!("(127.0.0.1 only; Ctrl-C stops it)");
    if wasm_path().is_none() {
        eprintln!("warning: {WASM_MISSING}; the page cannot read the file without it");
    }
    std::io::stdout().flush()?;
    for (served, stream) in (1u64..).zip(listener.incoming()) {
        // A client that misbehaves affects its own connection only.
        if let Ok(stream) = stream {
            let _ = respond(stream, &asset);
        }
        if args.max_requests.is_some_and(|m| served >= m) {
            break;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn asset(gltf: bool) -> Asset {
        Asset {
            dir: PathBuf::from("/data"),
            name: if gltf { "scene one.gltf" } else { "baked.glb" }.into(),
            gltf,
        }
    }

    #[test]
    fn every_web_module_and_kernel_is_embedded() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        let mut wanted = Vec::new();
        for (dir, ext) in [
            ("web/src", "js"),
            ("web/src", "wgsl"),
            ("web/src/three", "js"),
            ("runtime/src/gpu", "wgsl"),
        ] {
            for entry in std::fs::read_dir(root.join(dir)).unwrap() {
                let path = entry.unwrap().path();
                if path.extension().is_some_and(|e| e == ext) {
                    let name = path.file_name().unwrap().to_string_lossy().into_owned();
                    wanted.push(format!("/{dir}/{name}"));
                }
            }
        }
        assert!(wanted.len() > 20, "{wanted:?}");
        for url in wanted {
            assert!(
                EMBEDDED.iter().any(|(u, _)| *u == url),
                "{url} is not embedded in hce serve"
            );
        }
    }

    #[test]
    fn requests_reach_the_page_the_kernels_and_the_asset_only() {
        let a = asset(false);
        assert_eq!(
            route("/", &a),
            Reply::Redirect("/web/viewer.html?url=/file/baked.glb".into())
        );
        assert!(matches!(
            route("/web/viewer.html?url=x", &a),
            Reply::Embedded(_, "text/html; charset=utf-8")
        ));
        assert!(matches!(
            route("/runtime/src/gpu/loop.wgsl", &a),
            Reply::Embedded(b, _) if b.starts_with(b"//")
        ));
        assert_eq!(
            route("/file/baked.glb", &a),
            Reply::File("/data/baked.glb".into(), "model/gltf-binary")
        );
        // Nothing else of the directory, and nothing outside it.
        assert_eq!(
            route("/file/other.glb", &a),
            Reply::Status(404, "not found")
        );
        assert_eq!(
            route("/file/../etc/passwd", &a),
            Reply::Status(404, "not found")
        );
        assert_eq!(route("/file/%2e%2e/x", &a), Reply::Status(404, "not found"));
        assert_eq!(
            route("/runtime/src/gpu/wgsl.rs", &a),
            Reply::Status(404, "not found")
        );
        // A .gltf's buffers beside it are served, by their escaped names too.
        let g = asset(true);
        assert_eq!(g.url(), "/file/scene%20one.gltf");
        assert_eq!(
            route("/file/scene%20one.gltf", &g),
            Reply::File("/data/scene one.gltf".into(), "model/gltf+json")
        );
        assert_eq!(
            route("/file/buffers/a.bin", &g),
            Reply::File("/data/buffers/a.bin".into(), "application/octet-stream")
        );
        assert_eq!(route("/file/%zz", &g), Reply::Status(400, "bad path"));
    }

    #[test]
    fn the_wasm_is_served_from_hce_wasm_as_application_wasm() {
        let dir = tempfile::tempdir().unwrap();
        let wasm = dir.path().join("built.wasm");
        std::fs::write(&wasm, b"\0asm").unwrap();
        // Only this test sets HCE_WASM, and only `wasm_path` reads it.
        std::env::set_var("HCE_WASM", &wasm);
        let reply = route("/web/src/hce.wasm?v=1", &asset(false));
        std::env::remove_var("HCE_WASM");
        assert_eq!(reply, Reply::File(wasm, "application/wasm"));
    }

    #[test]
    fn a_real_connection_gets_the_asset_bytes() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("a.hce");
        std::fs::write(&file, b"\x89HCE bytes").unwrap();
        let listener = TcpListener::bind((Ipv4Addr::LOCALHOST, 0)).unwrap();
        let port = listener.local_addr().unwrap().port();
        let a = Asset {
            dir: dir.path().to_path_buf(),
            name: "a.hce".into(),
            gltf: false,
        };
        let server = std::thread::spawn(move || {
            let (stream, _) = listener.accept().unwrap();
            respond(stream, &a).unwrap();
        });
        let mut client = TcpStream::connect((Ipv4Addr::LOCALHOST, port)).unwrap();
        client
            .write_all(b"GET /file/a.hce HTTP/1.1\r\nHost: x\r\n\r\n")
            .unwrap();
        let mut reply = Vec::new();
        client.read_to_end(&mut reply).unwrap();
        server.join().unwrap();
        let text = String::from_utf8_lossy(&reply);
        assert!(text.starts_with("HTTP/1.1 200 OK\r\n"), "{text}");
        assert!(text.contains("Content-Length: 10\r\n"), "{text}");
        assert!(reply.ends_with(b"\x89HCE bytes"));
    }
}
