//! `cgnodes f3d-project DIR`: runs a Framework3D project folder as the framework does. For
//! each frame the geometry graph (`GeoNodeSystem.json`) runs and its Write USD files become
//! the stage's geometry layers; the composition graph (`CompositionGraph.json`) adds its
//! lights and merged layers (run once: its nodes do not depend on time); the stage is written
//! as `OUT/stage_NNNN.usda`; the render graph (`RenderGraph.json`) reads it through its
//! `render_scene_*` nodes and writes `OUT/frame_NNNN.png` where `render_present` sits.
//! Missing or empty graphs are skipped and said so. See docs/framework3d.md.

mod load;
mod stage;

use super::progress::{Monitor, Verbosity};
use super::{EXIT_INVALID, EXIT_NODE_FAILED, EXIT_USAGE};
use crate::exec::{Executor, RunOptions, RunReport};
use crate::graph::format::GraphFile;
use crate::node::FileEnv;
use crate::nodes::render::stage::{read_stage, Stage};
use crate::registry::Registry;
use crate::validate::ValidGraph;
use load::{load_project_graph, ProjectGraph};
use std::path::{Path, PathBuf};

/// `cgnodes f3d-project` options.
#[derive(clap::Args)]
pub(super) struct ProjectArgs {
    /// The project folder (GeoNodeSystem.json, CompositionGraph.json, RenderGraph.json).
    dir: PathBuf,
    /// Frame range A..B (inclusive); default 0..0.
    #[arg(long)]
    frames: Option<String>,
    /// Folders where input files (meshes, the dome light's texture) are also looked for.
    #[arg(long = "assets")]
    assets: Vec<PathBuf>,
    /// JSON file mapping custom Framework3D node names onto cgnodes nodes.
    #[arg(long = "f3d-aliases")]
    f3d_aliases: Option<PathBuf>,
    /// Output folder: frame_NNNN.png, stage_NNNN.usda, geometry/ (the Write USD layers).
    #[arg(long, default_value = "out")]
    out: PathBuf,
    /// Image width of the default camera, pixels.
    #[arg(long, default_value_t = 640)]
    width: u32,
    /// Image height of the default camera, pixels.
    #[arg(long, default_value_t = 480)]
    height: u32,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Print only errors.
    #[arg(long, short)]
    quiet: bool,
    /// Print each node's status.
    #[arg(long, short)]
    verbose: bool,
}

const GEOMETRY: &str = "GeoNodeSystem.json";
const COMPOSITION: &str = "CompositionGraph.json";
const RENDER: &str = "RenderGraph.json";

/// Why a project run stopped, with the exit code each reason gives.
#[derive(Debug, thiserror::Error)]
enum ProjectError {
    /// Bad options or an unusable output folder.
    #[error("{0}")]
    Usage(String),
    /// A graph or a layer that does not load or validate.
    #[error("{0}")]
    Invalid(String),
    /// A file the run writes could not be written.
    #[error("{0}")]
    Failed(String),
}

impl ProjectError {
    fn code(&self) -> i32 {
        match self {
            ProjectError::Usage(_) => EXIT_USAGE,
            ProjectError::Invalid(_) => EXIT_INVALID,
            ProjectError::Failed(_) => EXIT_NODE_FAILED,
        }
    }
}

/// `cgnodes f3d-project DIR ...`.
pub(super) fn cmd(registry: &Registry, args: ProjectArgs) -> i32 {
    match run(registry, &args) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e}");
            e.code()
        }
    }
}

/// The three graphs in turn: geometry every frame, composition once, then per frame the
/// stage and the render graph.
fn run(registry: &Registry, args: &ProjectArgs) -> Result<i32, ProjectError> {
    let (f0, f1) = check_args(args)?;
    let aliases = match &args.f3d_aliases {
        Some(p) => super::read_aliases(p).map_err(|e| ProjectError::Usage(e.to_string()))?,
        None => Default::default(),
    };
    let load = |name| load_project_graph(&args.dir, name, &aliases, registry);
    let (geo, comp, render) = (load(GEOMETRY)?, load(COMPOSITION)?, load(RENDER)?);
    if !args.quiet {
        say_skipped(
            &args.dir,
            [(GEOMETRY, &geo), (COMPOSITION, &comp), (RENDER, &render)],
        );
    }
    std::fs::create_dir_all(&args.out)
        .map_err(|e| ProjectError::Usage(format!("{}: {e}", args.out.display())))?;
    let mut p = Project {
        args,
        registry,
        exec: Executor::new(args.threads, None).map_err(|e| ProjectError::Usage(e.to_string()))?,
        monitor: Monitor::new(Verbosity::from_flags(args.quiet, args.verbose)),
        code: 0,
    };
    let layers = p.geometry(&geo, f0, f1)?;
    let composition = p.composition(&comp, f0)?;
    p.frames(&render, &layers, &composition, f0)?;
    Ok(p.code)
}

/// Checks the folder, image size and frame range; returns the range.
fn check_args(args: &ProjectArgs) -> Result<(i64, i64), ProjectError> {
    let usage = ProjectError::Usage;
    if !args.dir.is_dir() {
        return Err(usage(format!("{}: not a folder", args.dir.display())));
    }
    if !(1..=16384).contains(&args.width) || !(1..=16384).contains(&args.height) {
        return Err(usage("--width and --height must lie in 1..=16384".into()));
    }
    let (f0, f1) = match args.frames.as_deref().map(crate::graph::parse_frames) {
        None => (0, 0),
        Some(r) => r.map_err(usage)?,
    };
    // One stage per frame is kept until rendering: bound the range.
    if f1.checked_sub(f0).is_none_or(|n| n >= 100_000) {
        return Err(usage(format!(
            "--frames {f0}..{f1}: at most 100000 frames per run"
        )));
    }
    Ok((f0, f1))
}

/// Says which graphs are not in the project and which are empty.
fn say_skipped(dir: &Path, graphs: [(&str, &ProjectGraph); 3]) {
    let with = |want: fn(&ProjectGraph) -> bool| -> Vec<&str> {
        graphs
            .iter()
            .filter(|(_, g)| want(g))
            .map(|(n, _)| *n)
            .collect()
    };
    let missing = with(|g| matches!(g, ProjectGraph::Missing));
    let empty = with(|g| matches!(g, ProjectGraph::Empty));
    if !missing.is_empty() {
        eprintln!(
            "{}: not in the project: {}",
            dir.display(),
            missing.join(", ")
        );
    }
    if !empty.is_empty() {
        eprintln!(
            "{}: empty graphs (nothing to run): {}",
            dir.display(),
            empty.join(", ")
        );
    }
}

/// A project run: what every graph runs with, and the exit code so far.
struct Project<'a> {
    args: &'a ProjectArgs,
    registry: &'a Registry,
    exec: Executor,
    monitor: Monitor,
    code: i32,
}

impl Project<'_> {
    /// Run options writing under `out`, reading from the project and the asset folders.
    fn opts(&self, out: PathBuf) -> RunOptions {
        RunOptions {
            files: FileEnv {
                graph_dir: self.args.dir.clone(),
                asset_dirs: self.args.assets.clone(),
                out_dir: out,
                allow_write_anywhere: false,
            },
            progress: self.monitor.progress_fn(),
            log: self.monitor.log_fn(),
            ..Default::default()
        }
    }

    /// Validates one of the project's graphs, `spec` standing in for its imported nodes.
    fn validate(
        &self,
        file: &Path,
        spec: GraphFile,
        hash: &str,
    ) -> Result<ValidGraph, ProjectError> {
        let g = crate::graph::Graph {
            file: file.to_path_buf(),
            dir: self.args.dir.clone(),
            spec,
            hash: hash.to_string(),
        };
        crate::validate::validate_with(&g, self.registry, &self.args.assets).map_err(|errs| {
            // Each error names the file already.
            ProjectError::Invalid(
                errs.iter()
                    .map(|e| e.to_string())
                    .collect::<Vec<_>>()
                    .join("\n"),
            )
        })
    }

    /// Prints a run's errors (or its summary) and notes a failure in the exit code.
    fn report(&mut self, r: &RunReport, what: &str) {
        let quiet = self.args.quiet;
        self.monitor.suspend(|| {
            for e in r.errors() {
                eprintln!("error: {e}");
            }
            if !quiet && r.ok() {
                let written: usize = r.nodes.iter().map(|n| n.written.len()).sum();
                eprintln!(
                    "[frame {}] {what}: {} nodes, {written} files written in {:.1} ms",
                    r.frame,
                    r.nodes.len(),
                    r.total_ms
                );
            }
        });
        if !r.ok() {
            self.code = EXIT_NODE_FAILED;
        }
    }

    /// 1. Geometry, every frame: the Write USD layers of each frame, sorted.
    fn geometry(
        &mut self,
        geo: &ProjectGraph,
        f0: i64,
        f1: i64,
    ) -> Result<Vec<Vec<PathBuf>>, ProjectError> {
        let mut layers: Vec<Vec<PathBuf>> = vec![Vec::new(); (f1 - f0 + 1) as usize];
        let ProjectGraph::Graph {
            file, spec, hash, ..
        } = geo
        else {
            return Ok(layers);
        };
        let valid = self.validate(file, (**spec).clone(), hash)?;
        let o = self.opts(self.args.out.join("geometry"));
        self.monitor.start_frames(f0, f1);
        for frame in f0..=f1 {
            self.monitor.set_prefix(format!("[frame {frame}] "));
            let r = self.exec.run(&valid, &o, frame);
            self.report(&r, "geometry");
            let mut written: Vec<PathBuf> = r
                .nodes
                .iter()
                .flat_map(|n| n.written.iter().cloned())
                .filter(|p| {
                    p.extension()
                        .is_some_and(|e| e.eq_ignore_ascii_case("usda"))
                })
                .collect();
            written.sort();
            written.dedup();
            layers[(frame - f0) as usize] = written;
            self.monitor.frame_done(f0, f1, frame);
        }
        Ok(layers)
    }

    /// 2. Composition, once: the layers of its light and merge nodes, merged.
    fn composition(&mut self, comp: &ProjectGraph, f0: i64) -> Result<Stage, ProjectError> {
        let mut composition = Stage::default();
        let ProjectGraph::Graph {
            file, spec, hash, ..
        } = comp
        else {
            return Ok(composition);
        };
        let valid = self.validate(file, (**spec).clone(), hash)?;
        let ids: Vec<String> = valid
            .nodes
            .iter()
            .filter(|n| ["stage_light", "stage_merge"].contains(&n.decl.type_name.as_str()))
            .map(|n| n.id.clone())
            .collect();
        if ids.is_empty() {
            return Ok(composition);
        }
        let mut o = self.opts(self.args.out.clone());
        o.targets = Some(ids.clone());
        o.read_outputs = ids.iter().map(|i| format!("{i}.layer")).collect();
        let r = self.exec.run(&valid, &o, f0);
        self.report(&r, "composition");
        for id in &ids {
            let Some(crate::types::Value::String(t)) =
                r.outputs.get(id).and_then(|o| o.get("layer"))
            else {
                continue;
            };
            let s = read_stage(t).map_err(|e| {
                ProjectError::Invalid(format!(
                    "{}: node '{id}': its layer does not read back: {e}",
                    file.display()
                ))
            })?;
            composition.merge(s);
        }
        Ok(composition)
    }

    /// The render graph with its stage size and present fallback set: only the stage path
    /// changes from frame to frame.
    fn render_base(&self, render: &ProjectGraph) -> Option<GraphFile> {
        let ProjectGraph::Graph {
            file, raw, spec, ..
        } = render
        else {
            return None;
        };
        let mut spec = (**spec).clone();
        for n in spec.nodes.values_mut() {
            if n.node_type == "stage_load" {
                n.params
                    .insert("width".into(), serde_json::json!(self.args.width));
                n.params
                    .insert("height".into(), serde_json::json!(self.args.height));
            }
        }
        for w in crate::f3d::present::link_present_fallback(raw, &mut spec, self.registry) {
            eprintln!("warning: {}: {w}", file.display());
        }
        Some(spec)
    }

    /// Steps 3 and 4: the camera's framing covers the geometry of every frame; then per frame the
    /// stage, and the render graph reading it.
    fn frames(
        &mut self,
        render: &ProjectGraph,
        layers: &[Vec<PathBuf>],
        composition: &Stage,
        f0: i64,
    ) -> Result<(), ProjectError> {
        let args = self.args;
        // (The layers are read twice rather than all kept in memory.)
        let mut bounds = composition.bounds();
        for files in layers {
            bounds = stage::union(bounds, stage::geometry_stage(files)?.bounds());
        }
        let render_base = self.render_base(render);
        let f1 = f0 + layers.len() as i64 - 1;
        self.monitor.start_frames(f0, f1);
        for (k, files) in layers.iter().enumerate() {
            let frame = f0 + k as i64;
            let g = stage::geometry_stage(files)?;
            self.monitor.set_prefix(format!("[frame {frame}] "));
            let st = stage::frame_stage(g, composition, bounds, (args.width, args.height));
            let stage_path = args.out.join(format!("stage_{frame:04}.usda"));
            stage::write(&st, &stage_path)?;
            if !args.quiet {
                eprintln!("[frame {frame}] wrote {}", stage_path.display());
            }
            if let (ProjectGraph::Graph { file, hash, .. }, Some(base)) = (render, &render_base) {
                self.render(file, hash, base, &stage_path, frame)?;
            }
            self.monitor.frame_done(f0, f1, frame);
        }
        Ok(())
    }

    /// Runs the render graph `base` of `file` for `frame`, reading the stage at `stage_path`.
    fn render(
        &mut self,
        file: &Path,
        hash: &str,
        base: &GraphFile,
        stage_path: &Path,
        frame: i64,
    ) -> Result<(), ProjectError> {
        let mut spec = base.clone();
        let abs = std::fs::canonicalize(stage_path).unwrap_or(stage_path.to_path_buf());
        for n in spec.nodes.values_mut() {
            if n.node_type == "stage_load" {
                n.params
                    .insert("path".into(), serde_json::json!(abs.to_string_lossy()));
            }
        }
        let valid = self.validate(file, spec, hash)?;
        let r = self
            .exec
            .run(&valid, &self.opts(self.args.out.clone()), frame);
        self.report(&r, "render");
        Ok(())
    }
}
