//! `cgnodes validate`, and the loading every graph command shares: read the graph (a
//! Framework3D tree is imported against the registry), apply `--set`, validate, and print
//! every error with the exit code to return.

use super::{GraphArgs, EXIT_INVALID, EXIT_USAGE};
use crate::f3d::Aliases;
use crate::graph::{self, apply_sets, Graph};
use crate::registry::Registry;
use crate::validate::{validate_needed, validate_with, GraphError, ValidGraph};
use std::path::{Path, PathBuf};

/// `cgnodes validate GRAPH [--set ...] [--assets DIR] [--f3d-aliases FILE]`.
/// Every node is checked, needed by an output or not: a user validates to find every
/// mistake before a long run. With `--target`, problems in nodes the targets do not need are
/// warnings, as in `run`.
pub(super) fn cmd(registry: &Registry, args: &GraphArgs, targets: &[String]) -> i32 {
    let loaded = if targets.is_empty() {
        load_whole(registry, args)
    } else {
        load_args(registry, args, Some(targets))
    };
    match loaded {
        Ok((g, _)) => {
            println!("{}: ok ({} nodes)", args.graph.display(), g.nodes.len());
            0
        }
        Err(code) => code,
    }
}

/// Loads and validates the graph of `run`, `validate` or `dot` from their shared options
/// (`--set`, `--assets`, `--f3d-aliases`); `Err` is the exit code, the errors are printed.
/// Only the nodes that `targets` (default: the graph's outputs) need must validate; problems
/// in the others are printed as warnings and those nodes are left out.
pub(super) fn load_args(
    registry: &Registry,
    args: &GraphArgs,
    targets: Option<&[String]>,
) -> Result<(ValidGraph, Option<(i64, i64)>), i32> {
    let aliases = aliases_of(args)?;
    load_checked(registry, &args.graph, &args.set, &aliases, |g| {
        let (valid, warnings) = validate_needed(g, registry, &args.assets, targets)?;
        for w in &warnings {
            eprintln!("warning: {w}");
        }
        if !warnings.is_empty() {
            eprintln!(
                "warning: {} problem{} in nodes the requested outputs do not need; those nodes do not run",
                warnings.len(),
                if warnings.len() == 1 { "" } else { "s" }
            );
        }
        Ok(valid)
    })
}

/// The `--f3d-aliases` file's aliases (none without the option); `Err` is the exit code, the
/// error printed.
fn aliases_of(args: &GraphArgs) -> Result<Aliases, i32> {
    match args.f3d_aliases.as_deref().map(read_aliases).transpose() {
        Ok(a) => Ok(a.unwrap_or_default()),
        Err(e) => {
            eprintln!("error: {e}");
            Err(EXIT_USAGE)
        }
    }
}

/// Loads and validates every node of the graph from `validate`'s options; `Err` is the exit
/// code, the errors are printed.
fn load_whole(
    registry: &Registry,
    args: &GraphArgs,
) -> Result<(ValidGraph, Option<(i64, i64)>), i32> {
    let aliases = aliases_of(args)?;
    load_valid_with(registry, &args.graph, &args.set, &aliases, &args.assets)
}

/// Loads, applies overrides and validates, printing errors; `Err` is the exit code.
pub fn load_valid(registry: &Registry, path: &Path, sets: &[String]) -> Result<ValidGraph, i32> {
    load_valid_with(registry, path, sets, &Aliases::default(), &[]).map(|(g, _)| g)
}

/// Reads Framework3D aliases (`--f3d-aliases FILE`).
pub fn read_aliases(p: &Path) -> Result<Aliases, super::FileError> {
    let t = std::fs::read_to_string(p).map_err(super::FileError::at(p))?;
    serde_json::from_str(&t).map_err(super::FileError::at(p))
}

/// Like `load_valid`, with aliases for custom Framework3D node names; also returns the
/// graph's own frame range (`meta.frames`), read from the same load.
pub fn load_valid_with(
    registry: &Registry,
    path: &Path,
    sets: &[String],
    aliases: &Aliases,
    assets: &[PathBuf],
) -> Result<(ValidGraph, Option<(i64, i64)>), i32> {
    load_checked(registry, path, sets, aliases, |g| {
        validate_with(g, registry, assets)
    })
}

/// Reads the graph, applies `--set` and checks it with `check`; also returns the graph's
/// own frame range.
fn load_checked(
    registry: &Registry,
    path: &Path,
    sets: &[String],
    aliases: &Aliases,
    check: impl FnOnce(&Graph) -> Result<ValidGraph, Vec<GraphError>>,
) -> Result<(ValidGraph, Option<(i64, i64)>), i32> {
    let mut g = match graph::load_with(path, aliases, registry) {
        Ok(g) => g,
        Err(e) => {
            eprintln!("error: {e}");
            return Err(EXIT_INVALID);
        }
    };
    if let Err(e) = apply_sets(&mut g, sets) {
        eprintln!("error: {e}");
        return Err(EXIT_USAGE);
    }
    let hint = g.spec.frames_hint();
    let valid = check(&g).map_err(|errs| {
        print_graph_errors(&errs);
        EXIT_INVALID
    })?;
    Ok((valid, hint))
}

fn print_graph_errors(errs: &[GraphError]) {
    for e in errs {
        eprintln!("error: {e}");
    }
    eprintln!(
        "{} error{} found; nothing was run",
        errs.len(),
        if errs.len() == 1 { "" } else { "s" }
    );
}
