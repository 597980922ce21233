//! Where a run reads and writes files: input paths resolve against the graph's folder and
//! the asset folders; output paths stay under the output directory unless allowed, with
//! `{frame}` patterns substituted.

use std::path::{Path, PathBuf};

/// Where a run reads and writes files.
#[derive(Clone, Debug)]
pub struct FileEnv {
    /// Folder of the graph file: relative input paths resolve here.
    pub graph_dir: PathBuf,
    /// Further folders searched for input files (`--assets`).
    pub asset_dirs: Vec<PathBuf>,
    /// Output directory: writer nodes write under it.
    pub out_dir: PathBuf,
    /// Lets writers use absolute paths and `..` (off by default).
    pub allow_write_anywhere: bool,
}

impl Default for FileEnv {
    fn default() -> Self {
        FileEnv {
            graph_dir: ".".into(),
            asset_dirs: Vec::new(),
            out_dir: "out".into(),
            allow_write_anywhere: false,
        }
    }
}

impl FileEnv {
    /// Resolves an input path: absolute as is, else against the graph's folder, then the
    /// asset folders; the first that exists wins (the graph's folder when none does).
    pub fn input_path(&self, p: &str) -> PathBuf {
        let path = Path::new(p);
        if path.is_absolute() {
            return path.to_path_buf();
        }
        let first = self.graph_dir.join(path);
        if first.exists() {
            return first;
        }
        for d in &self.asset_dirs {
            let c = d.join(path);
            if c.exists() {
                return c;
            }
        }
        first
    }

    /// Whether `path` lies inside the graph's folder, an asset folder or the output directory
    /// (after resolving symbolic links and `..`). Nodes quote the content of such files in
    /// their errors, but not of files elsewhere, so a graph cannot use an error message to
    /// read an arbitrary file (issue 23).
    pub fn is_within_run_folders(&self, path: &Path) -> bool {
        let Ok(p) = path.canonicalize() else {
            return false;
        };
        std::iter::once(&self.graph_dir)
            .chain(&self.asset_dirs)
            .chain(std::iter::once(&self.out_dir))
            .filter_map(|d| d.canonicalize().ok())
            .any(|d| p.starts_with(d))
    }

    /// Resolves an output path under the output directory, substituting `{frame}` and
    /// `{frame:04}`; refuses absolute paths and `..` unless writes anywhere are allowed.
    pub fn output_path(&self, p: &str, frame: i64) -> Result<PathBuf, String> {
        let p = substitute_frame(p, frame)?;
        let path = Path::new(&p);
        if !self.allow_write_anywhere {
            if path.is_absolute() {
                return Err(format!(
                    "'{p}' is absolute; outputs go under the output directory (use --allow-write-anywhere to permit this)"
                ));
            }
            if path.components().any(|c| {
                !matches!(
                    c,
                    std::path::Component::Normal(_) | std::path::Component::CurDir
                )
            }) {
                return Err(format!(
                    "'{p}' leaves the output directory; outputs go under it (use --allow-write-anywhere to permit this)"
                ));
            }
        }
        if p.is_empty() {
            return Err("empty output path".into());
        }
        Ok(if path.is_absolute() {
            path.to_path_buf()
        } else {
            self.out_dir.join(path)
        })
    }
}

/// The widest zero-padded frame number a path may ask for (`{frame:020}`): wider widths are
/// refused rather than formatted (a width past 65,535 would panic in `format!`).
pub const MAX_FRAME_WIDTH: usize = 20;

/// Replaces `{frame}` and `{frame:0N}` in a path.
pub fn substitute_frame(p: &str, frame: i64) -> Result<String, String> {
    let mut out = String::new();
    let mut rest = p;
    while let Some(i) = rest.find("{frame") {
        out.push_str(&rest[..i]);
        let tail = &rest[i..];
        let end = tail
            .find('}')
            .ok_or_else(|| format!("unclosed '{{' in '{p}'"))?;
        let spec = &tail[6..end];
        if spec.is_empty() {
            out.push_str(&frame.to_string());
        } else if let Some(w) = spec.strip_prefix(":0").or_else(|| spec.strip_prefix(':')) {
            let w: usize = w
                .parse()
                .ok()
                .filter(|w| *w <= MAX_FRAME_WIDTH)
                .ok_or_else(|| {
                    format!(
                        "bad frame format '{{frame{spec}}}' in '{p}' (a width of at most {MAX_FRAME_WIDTH} digits)"
                    )
                })?;
            out.push_str(&format!("{frame:0w$}"));
        } else {
            return Err(format!("bad frame format '{{frame{spec}}}' in '{p}'"));
        }
        rest = &tail[end + 1..];
    }
    out.push_str(rest);
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_patterns() {
        assert_eq!(substitute_frame("a_{frame}.obj", 7).unwrap(), "a_7.obj");
        assert_eq!(
            substitute_frame("a_{frame:04}.obj", 7).unwrap(),
            "a_0007.obj"
        );
        assert!(substitute_frame("a_{frame:x}.obj", 7).is_err());
        // Hostile widths are an error, not a panic in format! (issue 23).
        let e = substitute_frame("a_{frame:070000}.obj", 7).unwrap_err();
        assert!(e.contains("at most 20 digits"), "{e}");
        assert_eq!(substitute_frame("a_{frame:020}", 7).unwrap().len(), 22);
    }

    #[test]
    fn run_folders_hold_their_files_and_nothing_else() {
        let root = tempfile::tempdir().unwrap();
        let [g, a, o, x] = ["graph", "assets", "out", "elsewhere"].map(|d| root.path().join(d));
        for d in [&g, &a, &o, &x] {
            std::fs::create_dir_all(d.join("sub")).unwrap();
            std::fs::write(d.join("sub/f.csv"), "T,Z\n").unwrap();
        }
        let env = FileEnv {
            graph_dir: g.clone(),
            asset_dirs: vec![a.clone()],
            out_dir: o.clone(),
            allow_write_anywhere: false,
        };
        for d in [&g, &a, &o] {
            assert!(env.is_within_run_folders(&d.join("sub/f.csv")), "{d:?}");
        }
        assert!(!env.is_within_run_folders(&x.join("sub/f.csv")));
        // `..` out of the graph's folder and missing files do not count.
        assert!(!env.is_within_run_folders(&g.join("../elsewhere/sub/f.csv")));
        assert!(!env.is_within_run_folders(&g.join("missing.csv")));
    }

    #[test]
    fn output_paths_stay_inside() {
        let env = FileEnv::default();
        assert!(env.output_path("../x.obj", 0).is_err());
        assert!(env.output_path("/tmp/x.obj", 0).is_err());
        assert!(env.output_path("a/../../x.obj", 0).is_err());
        assert_eq!(
            env.output_path("sub/x.obj", 0).unwrap(),
            Path::new("out/sub/x.obj")
        );
        let any = FileEnv {
            allow_write_anywhere: true,
            ..FileEnv::default()
        };
        assert!(any.output_path("/tmp/x.obj", 0).is_ok());
    }
}
