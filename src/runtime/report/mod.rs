//! The run report: one self-contained `report.html` in the output folder of `cgnodes run`
//! (and of `cgnodes sweep`), to look at what a run made. It holds the graph as SVG with each
//! node coloured by its status (`graph_svg`), the node timings and memory, and every written
//! file (`files`): images as thumbnails linking to the file, frame sequences as an animated
//! GIF, SVG charts inline, CSV tables as HTML tables, meshes as a rendered preview. Thumbnails
//! and animations go to `report_files/` beside it, referenced relatively; no JavaScript but a
//! few lines that mark images that failed to load (for the browser test). Over a frame range
//! the report is written once, at the end, covering every frame.

mod files;
pub use files::fit as fit_thumbnail;
pub mod graph_svg;

use crate::exec::{NodeStatus, RunReport};
use crate::validate::{ValidGraph, ValidNode};
use cgnodes_api::registry::MeshHooks;
use cgnodes_api::types::{Mesh, Value};
use rayon::prelude::*;
use std::collections::hash_map::Entry;
use std::collections::{BTreeMap, HashMap, VecDeque};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Condvar, Mutex};

/// A node's status over a run, the worst over its frames.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Status {
    /// Not needed by any requested output.
    Skipped,
    /// Served from the cache.
    Cached,
    /// Ran.
    Ran,
    /// Could not run (a node upstream failed, or a simulation stopped earlier).
    Blocked,
    /// Failed.
    Failed,
}

impl Status {
    /// The status of a node's report in one frame.
    pub fn of(s: &NodeStatus) -> Status {
        match s {
            NodeStatus::Ran => Status::Ran,
            NodeStatus::Cached => Status::Cached,
            NodeStatus::Skipped => Status::Skipped,
            NodeStatus::Failed(_) => Status::Failed,
            NodeStatus::Blocked { .. } | NodeStatus::Stopped { .. } => Status::Blocked,
        }
    }
    /// Its name, also the CSS class.
    pub fn name(self) -> &'static str {
        match self {
            Status::Skipped => "skipped",
            Status::Cached => "cached",
            Status::Ran => "ran",
            Status::Blocked => "blocked",
            Status::Failed => "failed",
        }
    }
    /// Its fill colour.
    pub fn color(self) -> &'static str {
        match self {
            Status::Skipped => "#eeeeee",
            Status::Cached => "#cfe2ff",
            Status::Ran => "#c7ecd2",
            Status::Blocked => "#fde2a7",
            Status::Failed => "#f8b4b4",
        }
    }
}

/// One node over every frame of a run.
#[derive(Clone, Debug, Default)]
pub struct NodeSummary {
    /// Node type.
    pub node_type: String,
    /// The worst status over the frames (`None` before the first frame).
    pub status: Option<Status>,
    /// Frames it ran in.
    pub ran: usize,
    /// Frames it was served from the cache.
    pub cached: usize,
    /// Total wall time, ms.
    pub ms: f64,
    /// Largest resident memory when it finished, KiB.
    pub rss_kib: u64,
    /// Files written, in order, without repeats.
    pub written: Vec<PathBuf>,
    /// The values files were written from (the first `MAX_KEPT_VALUES`), so the report draws
    /// them without reading the files back.
    pub values: HashMap<PathBuf, Value>,
    /// The first error, with its frame.
    pub error: Option<String>,
}

/// At most this many written values are kept per node (twice the frames an animation shows);
/// files past them are read back.
pub const MAX_KEPT_VALUES: usize = 2 * files::MAX_ANIM_FRAMES;

/// What the report needs from each frame's `RunReport`, gathered as the frames run (the
/// reports themselves hold every output and are not kept).
#[derive(Clone, Debug, Default)]
pub struct Collector {
    /// Per node id.
    pub nodes: BTreeMap<String, NodeSummary>,
    /// Frames run, first and last.
    pub frames: Option<(i64, i64)>,
    /// Total wall time, ms.
    pub total_ms: f64,
    /// Peak resident memory, KiB.
    pub peak_rss_kib: u64,
    /// Mesh thumbnails drawn while later frames run (`prefetch_previews`).
    pub prefetch: Option<Arc<Prefetch>>,
}

/// A node id and a file extension: the files of one sequence.
type SequenceKey = (String, String);

/// A sequence's first file, its mesh, and whether its thumbnail was started.
type SequenceStart = (PathBuf, Arc<Mesh>, bool);

/// One thumbnail to draw: the sequence frame `mesh` (file `path`) framed on `first` (file
/// `on`).
struct Job {
    on: PathBuf,
    first: Arc<Mesh>,
    path: PathBuf,
    mesh: Arc<Mesh>,
}

/// Mesh thumbnails drawn while the next frames run, so that a frame range's report has
/// little left to draw after the last frame. A sequence is framed on the first file its node
/// wrote with that extension. They are drawn by one thread at idle priority (`SCHED_IDLE` on
/// Linux): a run rarely keeps every core busy (the cloth of `bench/report_overhead.py` uses
/// 1.2 of 2), and an idle-priority thread takes only the time the run leaves, where jobs on
/// the run's own thread pool held up its parallel sections. What is left when the run ends
/// is drawn on every core (`wait`).
#[derive(Default)]
pub struct Prefetch {
    hooks: MeshHooks,
    done: Mutex<files::Prefetched>,
    /// The first mesh file per node and extension, its mesh (what a sequence is framed on),
    /// and whether it was drawn.
    firsts: Mutex<HashMap<SequenceKey, SequenceStart>>,
    /// Thumbnails waiting, whether the run has ended, and a signal for both.
    queue: (Mutex<(VecDeque<Job>, bool)>, Condvar),
    /// The drawing thread, started with the first job.
    worker: Mutex<Option<std::thread::JoinHandle<()>>>,
}

impl std::fmt::Debug for Prefetch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let n = self.done.lock().map_or(0, |d| d.len());
        write!(f, "Prefetch {{ {n} thumbnails }}")
    }
}

impl Prefetch {
    /// Queues the thumbnail of `mesh`, written to `path` by node `node`.
    fn start(self: &Arc<Self>, node: &str, path: &Path, mesh: &Arc<Mesh>) {
        if self.hooks.preview.is_none() {
            return;
        }
        // Only sequences are drawn ahead: the first file is kept, and drawn with the second.
        let key = (node.to_string(), files::ext_of(path));
        let (on, first, todo) = match self
            .firsts
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .entry(key)
        {
            Entry::Vacant(v) => {
                v.insert((path.to_path_buf(), mesh.clone(), false));
                return;
            }
            Entry::Occupied(mut o) => {
                let (on, first, drawn) = o.get_mut();
                let mut todo = vec![(path.to_path_buf(), mesh.clone())];
                if !*drawn {
                    todo.push((on.clone(), first.clone()));
                    *drawn = true;
                }
                (on.clone(), first.clone(), todo)
            }
        };
        {
            let mut q = self.queue.0.lock().unwrap_or_else(|e| e.into_inner());
            for (path, mesh) in todo {
                q.0.push_back(Job {
                    on: on.clone(),
                    first: first.clone(),
                    path,
                    mesh,
                });
            }
        }
        self.queue.1.notify_one();
        let mut w = self.worker.lock().unwrap_or_else(|e| e.into_inner());
        if w.is_none() {
            let me = self.clone();
            *w = std::thread::Builder::new()
                .name("report-thumbnails".into())
                .spawn(move || me.work())
                .ok();
        }
    }

    /// The drawing thread: takes jobs until the run ends.
    fn work(&self) {
        lower_priority();
        loop {
            let job = {
                let mut q = self.queue.0.lock().unwrap_or_else(|e| e.into_inner());
                loop {
                    if q.1 {
                        return;
                    }
                    if let Some(j) = q.0.pop_front() {
                        break j;
                    }
                    q = self.queue.1.wait(q).unwrap_or_else(|e| e.into_inner());
                }
            };
            self.draw(job);
        }
    }

    /// Draws one job at the size of a sequence's frames and keeps it.
    fn draw(&self, j: Job) {
        let Some(preview) = self.hooks.preview else {
            return;
        };
        let (w, h) = files::SEQUENCE_FRAME;
        let drawn = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            preview(&j.first, &j.mesh, w, h)
        }));
        if let Ok(Ok(img)) = drawn {
            let t = cgnodes_formats::animation::to_rgba8(&img);
            self.done
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .insert(j.path, (j.on, t));
        }
    }

    /// Ends the drawing thread and draws what it had not reached on every core.
    fn wait(&self) {
        let left: Vec<Job> = {
            let mut q = self.queue.0.lock().unwrap_or_else(|e| e.into_inner());
            q.1 = true;
            q.0.drain(..).collect()
        };
        self.queue.1.notify_all();
        left.into_par_iter().for_each(|j| self.draw(j));
        if let Some(h) = self.worker.lock().unwrap_or_else(|e| e.into_inner()).take() {
            let _ = h.join();
        }
    }
}

/// Puts the calling thread in Linux's idle scheduling class, so that it runs only on a core
/// nothing else wants (sched(7), `SCHED_IDLE`); elsewhere it keeps its priority.
fn lower_priority() {
    #[cfg(target_os = "linux")]
    {
        let param = libc::sched_param { sched_priority: 0 };
        // SAFETY: plain syscall on the calling thread (pid 0) with a valid parameter; a
        // failure only leaves the priority as it was.
        unsafe {
            libc::sched_setscheduler(0, libc::SCHED_IDLE, &param);
        }
    }
}

impl Collector {
    /// Draws mesh thumbnails through `hooks` as frames are added, while later frames run.
    pub fn prefetch_previews(&mut self, hooks: MeshHooks) {
        self.prefetch = Some(Arc::new(Prefetch {
            hooks,
            ..Default::default()
        }));
    }

    /// Adds one frame's report.
    pub fn add(&mut self, r: &RunReport) {
        self.frames = Some(match self.frames {
            None => (r.frame, r.frame),
            Some((a, b)) => (a.min(r.frame), b.max(r.frame)),
        });
        self.total_ms += r.total_ms;
        self.peak_rss_kib = self.peak_rss_kib.max(r.peak_rss_kib);
        for n in &r.nodes {
            let s = self.nodes.entry(n.id.clone()).or_default();
            s.node_type = n.node_type.clone();
            let st = Status::of(&n.status);
            s.status = Some(s.status.map_or(st, |o| o.max(st)));
            match st {
                Status::Ran => s.ran += 1,
                Status::Cached => s.cached += 1,
                _ => {}
            }
            s.ms += n.ms;
            s.rss_kib = s.rss_kib.max(n.rss_kib);
            for w in &n.written {
                if !s.values.contains_key(w) && !s.written.contains(w) {
                    s.written.push(w.clone());
                }
            }
            for (p, v) in &n.written_values {
                if s.values.len() < MAX_KEPT_VALUES {
                    s.values.insert(p.clone(), v.clone());
                    if let (Some(pf), Value::Mesh(m)) = (&self.prefetch, v) {
                        pf.start(&n.id, p, m);
                    }
                }
            }
            if let (NodeStatus::Failed(e), None) = (&n.status, &s.error) {
                s.error = Some(format!("frame {}: {e}", r.frame));
            }
        }
    }
}

/// Escapes text for HTML and SVG.
pub fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// The page around `body`: inline CSS, and a few lines of script marking images that did
/// not load (`data-broken`) and the page as loaded (`data-loaded` on `<body>`).
fn page(title: &str, body: &str) -> String {
    format!(
        r#"<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><meta name="viewport" content="width=device-width, initial-scale=1">
<title>{t}</title>
<style>
body{{font-family:system-ui,sans-serif;margin:1.5em auto;max-width:1100px;padding:0 1em;color:#223}}
h1{{font-size:1.5em}} h2{{font-size:1.2em;border-bottom:1px solid #ccd;margin-top:1.6em}} h3{{font-size:1em;margin:1em 0 .3em}}
.scroll{{overflow-x:auto}} table{{border-collapse:collapse;font-size:.85em}} td,th{{border:1px solid #ccd;padding:2px 6px;text-align:right}}
th{{background:#f0f2f6}} td.l,th.l{{text-align:left}} .files{{display:flex;flex-wrap:wrap;gap:12px}}
figure{{margin:0;border:1px solid #dde;padding:6px;background:#fafbfc;max-width:100%}} figcaption{{font-size:.8em;word-break:break-all;max-width:256px}}
.inline svg{{max-width:100%;height:auto}} .status{{display:inline-block;padding:0 6px;border-radius:4px}}
.err{{color:#a00;white-space:pre-wrap}} .muted{{color:#667;font-size:.85em}}
</style></head>
<body>
{body}
<script>
window.addEventListener('load', function () {{
  for (var i = 0; i < document.images.length; i++) {{
    var im = document.images[i];
    if (!(im.complete && im.naturalWidth > 0)) im.setAttribute('data-broken', '1');
  }}
  document.body.setAttribute('data-loaded', document.images.length);
}});
</script>
</body></html>
"#,
        t = esc(title)
    )
}

/// Writes `dir/report.html` (and `dir/report_files/`) for a run of `graph` over the frames
/// gathered in `c`; returns the report's path.
pub fn write_run_report(
    graph: &ValidGraph,
    c: &Collector,
    dir: &Path,
    hooks: MeshHooks,
) -> Result<PathBuf, ReportError> {
    let mut body = format!(
        "<h1>cgnodes run: {}</h1>\n",
        esc(&graph.file.display().to_string())
    );
    let frames = match c.frames {
        Some((a, b)) if a != b => format!("frames {a}..{b}"),
        Some((a, _)) => format!("frame {a}"),
        None => "no frame".into(),
    };
    let count = |s: Status| c.nodes.values().filter(|n| n.status == Some(s)).count();
    body.push_str(&format!(
        "<p>{frames}; {:.1} ms in total; peak memory {:.1} MiB. Nodes: {}.</p>\n",
        c.total_ms,
        c.peak_rss_kib as f64 / 1024.0,
        [
            Status::Ran,
            Status::Cached,
            Status::Failed,
            Status::Blocked,
            Status::Skipped
        ]
        .iter()
        .map(|&s| format!(
            "<span class=\"status\" style=\"background:{}\">{} {}</span>",
            s.color(),
            count(s),
            s.name()
        ))
        .collect::<Vec<_>>()
        .join(" ")
    ));
    for (id, n) in &c.nodes {
        if let Some(e) = &n.error {
            body.push_str(&format!(
                "<p class=\"err\">node '{}' ({}) failed: {}</p>\n",
                esc(id),
                esc(&n.node_type),
                esc(e)
            ));
        }
    }
    body.push_str("<h2>Graph</h2>\n<div class=\"scroll\">\n");
    let status = |i: usize| {
        c.nodes
            .get(&graph.nodes[i].id)
            .and_then(|n| n.status)
            .unwrap_or(Status::Skipped)
    };
    body.push_str(&graph_svg::graph_svg(graph, &status));
    body.push_str("</div>\n<h2>Outputs</h2>\n");
    let prefetched = match &c.prefetch {
        Some(pf) => {
            pf.wait();
            std::mem::take(&mut *pf.done.lock().unwrap_or_else(|e| e.into_inner()))
        }
        None => Default::default(),
    };
    let fr = files::FileRenderer::new(dir, hooks, prefetched)?;
    // Each node's files are drawn in parallel (thumbnails, previews, animations); the page
    // keeps the graph's order.
    let shown: Vec<(&ValidNode, &NodeSummary)> = graph
        .nodes
        .iter()
        .filter_map(|n| Some((n, c.nodes.get(&n.id)?)))
        .filter(|(_, s)| !s.written.is_empty())
        .collect();
    let any = !shown.is_empty();
    let parts: Vec<String> = shown
        .par_iter()
        .map(|(n, s)| {
            format!(
                "<h3>{} <span class=\"muted\">({})</span></h3>\n{}",
                esc(&n.id),
                esc(&n.decl.type_name),
                fr.render(&s.written, &s.values)
            )
        })
        .collect();
    for p in parts {
        body.push_str(&p);
    }
    if !any {
        body.push_str("<p>No file was written.</p>\n");
    }
    body.push_str(&timings_table(graph, c));
    write_page(dir, "cgnodes run", &body)
}

/// The per-node table: status, frames ran and cached, time, memory.
fn timings_table(graph: &ValidGraph, c: &Collector) -> String {
    let mut t = String::from(
        "<h2>Timings and memory</h2>\n<div class=\"scroll\"><table><tr><th class=\"l\">node</th><th class=\"l\">type</th><th class=\"l\">status</th><th>ran</th><th>cached</th><th>ms (all frames)</th><th>RSS MiB at end</th></tr>\n",
    );
    for n in &graph.nodes {
        let Some(s) = c.nodes.get(&n.id) else {
            continue;
        };
        let st = s.status.unwrap_or(Status::Skipped);
        t.push_str(&format!(
            "<tr><td class=\"l\">{}</td><td class=\"l\">{}</td><td class=\"l\" style=\"background:{}\">{}</td><td>{}</td><td>{}</td><td>{:.2}</td><td>{:.1}</td></tr>\n",
            esc(&n.id),
            esc(&s.node_type),
            st.color(),
            st.name(),
            s.ran,
            s.cached,
            s.ms,
            s.rss_kib as f64 / 1024.0
        ));
    }
    t.push_str("</table></div>\n<p class=\"muted\">RSS is the process's resident memory when the node finished (with --profile; 0 otherwise).</p>\n");
    t
}

/// Writes `dir/report.html` for a sweep: its chart and CSV (and any other `files`).
pub fn write_sweep_report(
    title: &str,
    files: &[PathBuf],
    dir: &Path,
    hooks: MeshHooks,
) -> Result<PathBuf, ReportError> {
    let mut body = format!("<h1>cgnodes sweep: {}</h1>\n", esc(title));
    let fr = files::FileRenderer::new(dir, hooks, Default::default())?;
    let parts: Vec<String> = files
        .par_iter()
        .filter(|f| f.is_file())
        .map(|f| fr.render(std::slice::from_ref(f), &HashMap::new()))
        .collect();
    for p in parts {
        body.push_str(&p);
    }
    write_page(dir, "cgnodes sweep", &body)
}

/// Why a report (or one of its figures) was not written.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// A file or folder of the report could not be written.
    #[error("{}: {source}", path.display())]
    Write {
        path: PathBuf,
        source: std::io::Error,
    },
    /// An image did not read or encode.
    #[error("{0}")]
    Image(String),
    /// A mesh file did not read.
    #[error("{0}")]
    Mesh(String),
    #[error("no mesh preview in this build")]
    NoPreview,
}

fn write_page(dir: &Path, title: &str, body: &str) -> Result<PathBuf, ReportError> {
    let path = dir.join("report.html");
    let html = page(title, body);
    if let Err(source) = cgnodes_api::io::write_atomic(&path, |w| w.write_all(html.as_bytes())) {
        return Err(ReportError::Write { path, source });
    }
    Ok(path)
}
