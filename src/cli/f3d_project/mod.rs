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
use crate::graph::Graph;
use crate::node::FileEnv;
use crate::nodes::render::stage::{read_stage, Stage};
use crate::registry::Registry;
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

fn validate(
    file: &Path,
    dir: &Path,
    spec: GraphFile,
    hash: &str,
    registry: &Registry,
    assets: &[PathBuf],
) -> Result<crate::validate::ValidGraph, String> {
    let g = Graph {
        file: file.to_path_buf(),
        dir: dir.to_path_buf(),
        spec,
        hash: hash.to_string(),
    };
    crate::validate::validate_with(&g, registry, assets).map_err(|errs| {
        // Each error names the file already.
        errs.iter()
            .map(|e| e.to_string())
            .collect::<Vec<_>>()
            .join("\n")
    })
}

/// `cgnodes f3d-project DIR ...`.
pub(super) fn cmd(registry: &Registry, args: ProjectArgs) -> i32 {
    match run(registry, &args) {
        Ok(code) => code,
        Err((code, msg)) => {
            eprintln!("error: {msg}");
            code
        }
    }
}

fn run(registry: &Registry, args: &ProjectArgs) -> Result<i32, (i32, String)> {
    let usage = |m: String| (EXIT_USAGE, m);
    let invalid = |m: String| (EXIT_INVALID, m);
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
    let aliases = match &args.f3d_aliases {
        Some(p) => super::read_aliases(p).map_err(usage)?,
        None => Default::default(),
    };
    let load = |name| load_project_graph(&args.dir, name, &aliases, registry).map_err(invalid);
    let (geo, comp, render) = (load(GEOMETRY)?, load(COMPOSITION)?, load(RENDER)?);
    let mut missing = Vec::new();
    let mut empty = Vec::new();
    for (name, g) in [(GEOMETRY, &geo), (COMPOSITION, &comp), (RENDER, &render)] {
        match g {
            ProjectGraph::Missing => missing.push(name),
            ProjectGraph::Empty => empty.push(name),
            ProjectGraph::Graph { .. } => {}
        }
    }
    if !args.quiet {
        if !missing.is_empty() {
            eprintln!(
                "{}: not in the project: {}",
                args.dir.display(),
                missing.join(", ")
            );
        }
        if !empty.is_empty() {
            eprintln!(
                "{}: empty graphs (nothing to run): {}",
                args.dir.display(),
                empty.join(", ")
            );
        }
    }
    std::fs::create_dir_all(&args.out)
        .map_err(|e| usage(format!("{}: {e}", args.out.display())))?;
    let exec = Executor::new(args.threads, None).map_err(usage)?;
    let monitor = Monitor::new(Verbosity::from_flags(args.quiet, args.verbose));
    let files = |out: PathBuf| FileEnv {
        graph_dir: args.dir.clone(),
        asset_dirs: args.assets.clone(),
        out_dir: out,
        allow_write_anywhere: false,
    };
    let opts = |out: PathBuf| RunOptions {
        files: files(out),
        progress: monitor.progress_fn(),
        log: monitor.log_fn(),
        ..Default::default()
    };
    let mut code = 0;
    let mut report = |r: &RunReport, what: &str| {
        monitor.suspend(|| {
            for e in r.errors() {
                eprintln!("error: {e}");
            }
            if !args.quiet && r.ok() {
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
            code = EXIT_NODE_FAILED;
        }
    };

    // 1. Geometry, every frame: the Write USD layers.
    let geo_dir = args.out.join("geometry");
    let mut layers: Vec<Vec<PathBuf>> = vec![Vec::new(); (f1 - f0 + 1) as usize];
    if let ProjectGraph::Graph {
        file, spec, hash, ..
    } = &geo
    {
        let valid = validate(
            file,
            &args.dir,
            (**spec).clone(),
            hash,
            registry,
            &args.assets,
        )
        .map_err(invalid)?;
        let o = opts(geo_dir.clone());
        monitor.start_frames(f0, f1);
        for frame in f0..=f1 {
            monitor.set_prefix(format!("[frame {frame}] "));
            let r = exec.run(&valid, &o, frame);
            report(&r, "geometry");
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
            monitor.frame_done(f0, f1, frame);
        }
    }
    // 2. Composition, once.
    let mut composition = Stage::default();
    if let ProjectGraph::Graph {
        file, spec, hash, ..
    } = &comp
    {
        let valid = validate(
            file,
            &args.dir,
            (**spec).clone(),
            hash,
            registry,
            &args.assets,
        )
        .map_err(invalid)?;
        let ids: Vec<String> = valid
            .nodes
            .iter()
            .filter(|n| ["stage_light", "stage_merge"].contains(&n.decl.type_name.as_str()))
            .map(|n| n.id.clone())
            .collect();
        if !ids.is_empty() {
            let mut o = opts(args.out.clone());
            o.targets = Some(ids.clone());
            o.read_outputs = ids.iter().map(|i| format!("{i}.layer")).collect();
            let r = exec.run(&valid, &o, f0);
            report(&r, "composition");
            for id in &ids {
                let Some(crate::types::Value::String(t)) =
                    r.outputs.get(id).and_then(|o| o.get("layer"))
                else {
                    continue;
                };
                let s = read_stage(t).map_err(|e| {
                    invalid(format!(
                        "{}: node '{id}': its layer does not read back: {e}",
                        file.display()
                    ))
                })?;
                composition.merge(s);
            }
        }
    }
    // 3. The camera's framing covers the geometry of every frame.
    // (The layers are read twice rather than all kept in memory.)
    let mut bounds = composition.bounds();
    for files in &layers {
        let s = stage::geometry_stage(files).map_err(invalid)?;
        bounds = stage::union(bounds, s.bounds());
    }
    // 4. Per frame: the stage, then the render graph. The render graph's present fallback
    // and stage size are set once; only the stage path changes from frame to frame.
    let render_base = match &render {
        ProjectGraph::Graph {
            file, raw, spec, ..
        } => {
            let mut spec = (**spec).clone();
            for n in spec.nodes.values_mut() {
                if n.node_type == "stage_load" {
                    n.params
                        .insert("width".into(), serde_json::json!(args.width));
                    n.params
                        .insert("height".into(), serde_json::json!(args.height));
                }
            }
            for w in crate::f3d::present::link_present_fallback(raw, &mut spec, registry) {
                eprintln!("warning: {}: {w}", file.display());
            }
            Some(spec)
        }
        _ => None,
    };
    monitor.start_frames(f0, f1);
    for (k, files) in layers.iter().enumerate() {
        let frame = f0 + k as i64;
        let g = stage::geometry_stage(files).map_err(invalid)?;
        monitor.set_prefix(format!("[frame {frame}] "));
        let st = stage::frame_stage(g, &composition, bounds, (args.width, args.height));
        let stage_path = args.out.join(format!("stage_{frame:04}.usda"));
        stage::write(&st, &stage_path).map_err(|e| (EXIT_NODE_FAILED, e))?;
        if !args.quiet {
            eprintln!("[frame {frame}] wrote {}", stage_path.display());
        }
        let (ProjectGraph::Graph { file, hash, .. }, Some(base)) = (&render, &render_base) else {
            monitor.frame_done(f0, f1, frame);
            continue;
        };
        let mut spec = base.clone();
        let abs = std::fs::canonicalize(&stage_path).unwrap_or(stage_path.clone());
        for n in spec.nodes.values_mut() {
            if n.node_type == "stage_load" {
                n.params
                    .insert("path".into(), serde_json::json!(abs.to_string_lossy()));
            }
        }
        let valid =
            validate(file, &args.dir, spec, hash, registry, &args.assets).map_err(invalid)?;
        let r = exec.run(&valid, &opts(args.out.clone()), frame);
        report(&r, "render");
        monitor.frame_done(f0, f1, frame);
    }
    Ok(code)
}
