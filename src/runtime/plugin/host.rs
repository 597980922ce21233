//! Finding plugins and adding their nodes to a registry: the search path (`--plugins`,
//! `CGNODES_PLUGIN_PATH`, the user's config folder), discovery of plugin folders, and
//! registration that never replaces a node already taken.

use super::{load, Plugin, MANIFEST, PATH_VAR};
use cgnodes_api::registry::Registry;
use std::path::{Path, PathBuf};

/// The user's plugin folder: `$XDG_CONFIG_HOME/cgnodes/plugins`, else
/// `$HOME/.config/cgnodes/plugins`.
pub fn user_dir() -> Option<PathBuf> {
    let base = std::env::var_os("XDG_CONFIG_HOME")
        .filter(|v| !v.is_empty())
        .map(PathBuf::from)
        .or_else(|| {
            std::env::var_os("HOME")
                .filter(|v| !v.is_empty())
                .map(|h| PathBuf::from(h).join(".config"))
        })?;
    Some(base.join("cgnodes").join("plugins"))
}

/// Where a plugin search folder comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Origin {
    /// `--plugins DIR` (must exist).
    Cli,
    /// `CGNODES_PLUGIN_PATH`.
    Env,
    /// The user's config folder (need not exist).
    User,
}

/// The folders searched for plugins, in order of precedence: the `--plugins` folders (which
/// must exist), then `CGNODES_PLUGIN_PATH`, then the user's folder. Each is either a plugin
/// folder (it holds a manifest) or a folder of plugin folders.
pub fn search_path(
    cli: &[PathBuf],
    env_path: Option<&std::ffi::OsStr>,
    user: Option<PathBuf>,
) -> Vec<(PathBuf, Origin)> {
    let mut v: Vec<(PathBuf, Origin)> = cli.iter().map(|p| (p.clone(), Origin::Cli)).collect();
    if let Some(e) = env_path {
        v.extend(
            std::env::split_paths(e)
                .filter(|p| !p.as_os_str().is_empty())
                .map(|p| (p, Origin::Env)),
        );
    }
    if let Some(u) = user {
        v.push((u, Origin::User));
    }
    v
}

/// Why the plugin search path could not be read: only `--plugins` folders fail the run.
#[derive(Debug, thiserror::Error)]
pub enum PluginPathError {
    /// A folder of the search path could not be listed.
    #[error("{}: {source}", .root.display())]
    Unreadable {
        /// The folder.
        root: PathBuf,
        /// The system's error.
        source: std::io::Error,
    },
    /// A `--plugins` folder does not exist.
    #[error("--plugins {}: no such folder", .0.display())]
    NoSuchFolder(PathBuf),
    /// A `--plugins` folder holds no manifest, itself or in its subfolders.
    #[error("--plugins {}: neither a plugin folder (no {MANIFEST}) nor a folder of plugins", .0.display())]
    NoPlugins(PathBuf),
}

/// The plugin folders under `root`: `root` itself if it holds a manifest, else its
/// subfolders that do, sorted by name.
pub fn discover(root: &Path) -> Result<Vec<PathBuf>, PluginPathError> {
    if root.join(MANIFEST).is_file() {
        return Ok(vec![root.to_path_buf()]);
    }
    let rd = std::fs::read_dir(root).map_err(|source| PluginPathError::Unreadable {
        root: root.into(),
        source,
    })?;
    let mut v: Vec<PathBuf> = rd
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.join(MANIFEST).is_file())
        .collect();
    v.sort();
    Ok(v)
}

/// Adds the nodes of plugin `p` to `registry`. A node whose name is taken (a built-in node or
/// an earlier plugin's) is not added; the returned warnings say so.
pub fn register(registry: &mut Registry, p: Plugin) -> Vec<String> {
    let mut warnings = Vec::new();
    for d in p.nodes {
        if let Some(old) = registry.get(&d.type_name) {
            warnings.push(format!(
                "plugin '{}' at {}: node '{}' is not added; the name is taken by {}",
                p.name,
                p.dir.display(),
                d.type_name,
                old.source
            ));
            continue;
        }
        registry.add_decl(d);
    }
    warnings
}

/// Adds every plugin found on the search path to `registry`. Fails when a `--plugins`
/// folder does not exist; other problems (a broken manifest, a taken name, a missing
/// folder on `CGNODES_PLUGIN_PATH`) are returned as warnings and the plugin is skipped.
pub fn load_all(
    registry: &mut Registry,
    search: &[(PathBuf, Origin)],
) -> Result<Vec<String>, PluginPathError> {
    let mut warnings = Vec::new();
    for (root, origin) in search {
        let explicit = &(*origin == Origin::Cli);
        if !root.exists() {
            match origin {
                Origin::Cli => return Err(PluginPathError::NoSuchFolder(root.clone())),
                Origin::Env => {
                    warnings.push(format!("{PATH_VAR}: {}: no such folder", root.display()))
                }
                Origin::User => {}
            }
            continue;
        }
        let dirs = match discover(root) {
            Ok(d) => d,
            Err(e) if *explicit => return Err(e),
            Err(e) => {
                warnings.push(e.to_string());
                continue;
            }
        };
        if dirs.is_empty() && *explicit {
            return Err(PluginPathError::NoPlugins(root.clone()));
        }
        for d in dirs {
            match load(&d) {
                Ok(p) => warnings.extend(register(registry, p)),
                Err(e) => warnings.push(format!("plugin not loaded: {e}")),
            }
        }
    }
    Ok(warnings)
}

/// The registry the command line uses: `base` plus the plugins from `--plugins` folders,
/// `CGNODES_PLUGIN_PATH` and the user's folder. Warnings go to stderr.
pub fn cli_registry(base: Registry, cli_dirs: &[PathBuf]) -> Result<Registry, PluginPathError> {
    let mut r = base;
    let search = search_path(cli_dirs, std::env::var_os(PATH_VAR).as_deref(), user_dir());
    for w in load_all(&mut r, &search)? {
        eprintln!("warning: {w}");
    }
    Ok(r)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn search_order_is_cli_then_env_then_user() {
        let env = std::env::join_paths(["/a", "/b"]).unwrap();
        let s = search_path(
            &[PathBuf::from("/cli")],
            Some(&env),
            Some(PathBuf::from("/home/u/.config/cgnodes/plugins")),
        );
        let names: Vec<_> = s.iter().map(|(p, o)| (p.to_str().unwrap(), *o)).collect();
        assert_eq!(
            names,
            [
                ("/cli", Origin::Cli),
                ("/a", Origin::Env),
                ("/b", Origin::Env),
                ("/home/u/.config/cgnodes/plugins", Origin::User)
            ]
        );
    }

    #[test]
    fn plugins_do_not_replace_builtin_nodes() {
        let d = tempfile::tempdir().unwrap();
        std::fs::write(
            d.path().join(MANIFEST),
            r#"{"name": "p", "protocol": 1, "command": ["x"], "nodes": [{"type": "math"}]}"#,
        )
        .unwrap();
        let mut r = Registry::new();
        r.add("math", |_| {}, |_| Ok(()));
        let w = load_all(&mut r, &[(d.path().to_path_buf(), Origin::Cli)]).unwrap();
        assert_eq!(w.len(), 1, "{w:?}");
        assert_eq!(r.get("math").unwrap().source, "builtin");
        assert!(load_all(&mut r, &[(d.path().join("nope"), Origin::Cli)]).is_err());
    }
}
