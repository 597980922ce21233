//! `cgnodes serve GRAPH`: a local web page for one graph (docs/serve.md). The page draws the
//! graph with each node's status and time, shows every output (images, meshes in a WebGL
//! viewer, charts, tables, frame sequences) and each node's parameters as widgets made from
//! its declaration. A changed widget is written into the graph file (only that value's bytes)
//! and the graph reruns with the same executor, so only what changed recomputes; saving the
//! file in an editor does the same. Progress and log lines stream to the page.
//!
//! Security: it listens on 127.0.0.1 unless `--host` says otherwise; every request needs the
//! random token printed at start (in the URL, then a cookie); requests whose `Host` or
//! `Origin` is not the served address are refused (DNS rebinding); the page reads only
//! `--out`, the graph file and the vendored viewer, and writes only the graph file.

mod edit;
mod http;
mod session;

use super::watch::{wait_quiet, FileWatch};
use super::{EXIT_INVALID, EXIT_USAGE};
use crate::registry::Registry;
use session::{Session, Setup};
use std::path::PathBuf;
use std::sync::mpsc;

/// `cgnodes serve` options.
#[derive(clap::Args)]
pub struct ServeArgs {
    /// The graph file.
    graph: PathBuf,
    /// Output directory; writer nodes write under it.
    #[arg(long, default_value = "out")]
    out: PathBuf,
    /// Port to listen on (0 picks a free one).
    #[arg(long, default_value_t = 8765)]
    port: u16,
    /// Address to listen on. Anything but a loopback address lets other machines run graphs
    /// that write files here: only on a network you trust.
    #[arg(long, default_value = "127.0.0.1")]
    host: String,
    /// Frame range A..B (default: the graph's own, else frame 0).
    #[arg(long)]
    frames: Option<String>,
    /// Further folders searched for input files (repeatable).
    #[arg(long = "assets", value_name = "DIR")]
    assets: Vec<PathBuf>,
    /// JSON file mapping custom Framework3D node names onto cgnodes nodes.
    #[arg(long = "f3d-aliases")]
    f3d_aliases: Option<PathBuf>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Print only the URL and errors.
    #[arg(long, hide = true)]
    quiet: bool,
}

/// Runs `serve` until interrupted; returns the exit code of a failure to start.
pub fn cmd(registry: &Registry, args: ServeArgs) -> i32 {
    let setup = match setup(&args) {
        Ok(s) => s,
        Err(code) => return code,
    };
    let (server, port) = match listen(&args) {
        Ok(l) => l,
        Err(code) => return code,
    };
    let session = match Session::new(registry, setup, args.threads) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return EXIT_USAGE;
        }
    };
    let token = http::new_token();
    let gate = http::Gate::new(&args.host, port, token.clone());
    announce(&args, port, &token);
    // Runs are queued on one channel: page edits and file changes alike.
    let (run_tx, run_rx) = mpsc::channel::<()>();
    let (file_tx, file_rx) = mpsc::channel::<PathBuf>();
    let watch = match FileWatch::new(move |p| {
        let _ = file_tx.send(p);
    }) {
        Ok(w) => w,
        Err(e) => {
            eprintln!("error: {e}");
            return EXIT_USAGE;
        }
    };
    let channels = Channels {
        run_tx,
        run_rx,
        file_rx,
    };
    serve(&session, &server, &gate, watch, channels)
}

/// What the session serves, from the options: the graph must exist, the frames and aliases
/// parse, the output folder can be made. `Err` is the exit code, the error printed.
fn setup(args: &ServeArgs) -> Result<Setup, i32> {
    if !args.graph.is_file() {
        eprintln!("error: {}: no such file", args.graph.display());
        return Err(EXIT_INVALID);
    }
    let frames = match args.frames.as_deref().map(crate::graph::parse_frames) {
        Some(Ok(r)) => Some(r),
        Some(Err(e)) => {
            eprintln!("error: {e}");
            return Err(EXIT_USAGE);
        }
        None => None,
    };
    let aliases = match args.f3d_aliases.as_deref().map(super::read_aliases) {
        Some(Ok(a)) => a,
        Some(Err(e)) => {
            eprintln!("error: {e}");
            return Err(EXIT_USAGE);
        }
        None => Default::default(),
    };
    if let Err(e) = std::fs::create_dir_all(&args.out) {
        eprintln!("error: {}: {e}", args.out.display());
        return Err(EXIT_USAGE);
    }
    Ok(Setup {
        graph: args.graph.clone(),
        out: args.out.clone(),
        assets: args.assets.clone(),
        frames,
        aliases,
    })
}

/// The HTTP server on `--host`/`--port` and the port it got (warning when the address is
/// not a loopback one). `Err` is the exit code, the error printed.
fn listen(args: &ServeArgs) -> Result<(tiny_http::Server, u16), i32> {
    let loopback = matches!(args.host.as_str(), "127.0.0.1" | "localhost" | "::1");
    if !loopback {
        eprintln!(
            "warning: --host {}: the page can run this graph and write files under {}; anyone who can reach this address and has the token can",
            args.host,
            args.out.display()
        );
    }
    let server = match tiny_http::Server::http((args.host.as_str(), args.port)) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: cannot listen on {}:{}: {e}", args.host, args.port);
            return Err(EXIT_USAGE);
        }
    };
    let port = server.server_addr().to_ip().map_or(args.port, |a| a.port());
    Ok((server, port))
}

/// Prints the page's URL with its token (on stdout, for scripts) and what is served.
fn announce(args: &ServeArgs, port: u16, token: &str) {
    let shown_host = if args.host == "::1" {
        "[::1]".to_string()
    } else {
        args.host.clone()
    };
    println!("http://{shown_host}:{port}/?token={token}");
    if !args.quiet {
        eprintln!(
            "serving {} (Ctrl-C stops); the page writes parameter changes into this file",
            args.graph.display()
        );
    }
}

/// The channels between the server's threads: runs asked for (by the page or a file
/// change), and the changed files the watch reports.
struct Channels {
    run_tx: mpsc::Sender<()>,
    run_rx: mpsc::Receiver<()>,
    file_rx: mpsc::Receiver<PathBuf>,
}

/// Serves until the server stops: a runner thread, a file-change thread and one thread per
/// request.
fn serve(
    session: &Session,
    server: &tiny_http::Server,
    gate: &http::Gate,
    watch: FileWatch,
    channels: Channels,
) -> i32 {
    let Channels {
        run_tx,
        run_rx,
        file_rx,
    } = channels;
    std::thread::scope(|scope| {
        // The runner: one run at a time; requests that arrive during a run make one more.
        // After each run the watch follows the graph's input files.
        let watch = std::sync::Mutex::new(watch);
        scope.spawn(move || {
            let mut watched = Vec::new();
            loop {
                session.run();
                let mut list = vec![session.setup.graph.clone()];
                list.extend(session.inputs());
                if list != watched {
                    watch.lock().unwrap_or_else(|e| e.into_inner()).set(&list);
                    watched = list;
                }
                if run_rx.recv().is_err() {
                    return;
                }
                while run_rx.try_recv().is_ok() {}
            }
        });
        // File changes: the graph file saved from an editor (a change the page made itself
        // has already run), or an input file.
        let tx = run_tx.clone();
        scope.spawn(move || loop {
            let changed = wait_quiet(&file_rx);
            if changed.is_empty() {
                return;
            }
            let graph = super::watch::normalize(&session.setup.graph);
            let only_graph = changed.iter().all(|p| *p == graph);
            if !only_graph || session.text_changed() {
                let _ = tx.send(());
            }
        });
        // Requests, each on its own thread (event streams stay open).
        let tx = run_tx.clone();
        scope.spawn(move || {
            for req in server.incoming_requests() {
                let tx = tx.clone();
                scope.spawn(move || http::handle(req, session, gate, &tx));
            }
        });
        drop(run_tx);
        0
    })
}
