//! The workspace's layout as the compiler cannot check it (issue 57): every source file under
//! `nodes/` is declared by a plain `mod` line (so it is compiled at all), and every node type
//! a node file registers is in the built-in registry (so a family's `register` lists it).

use crate::common::root;
use std::path::{Path, PathBuf};

/// Every `.rs` file under `dir`, recursively.
fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The module name `file` is declared under, and the files that may declare it: the crate
/// root declares its siblings; `x/mod.rs` and `x.rs` declare the files in `x/`.
fn declarers(file: &Path, crate_dir: &Path) -> (String, Vec<PathBuf>) {
    let stem = file.file_stem().unwrap().to_string_lossy().into_owned();
    let dir = file.parent().unwrap();
    let mut v = Vec::new();
    if dir == crate_dir {
        v.push(dir.join("lib.rs"));
    } else {
        v.push(dir.join("mod.rs"));
        v.push(dir.with_extension("rs"));
        if dir.parent() == Some(crate_dir) {
            v.push(crate_dir.join("lib.rs"));
        }
    }
    // `mod.rs` is declared by its folder's name in the folder above.
    if stem == "mod" {
        let name = dir.file_name().unwrap().to_string_lossy().into_owned();
        let up = dir.parent().unwrap();
        let mut w = vec![up.join("mod.rs"), up.with_extension("rs")];
        if up == crate_dir {
            w = vec![crate_dir.join("lib.rs")];
        }
        return (name, w);
    }
    (stem, v)
}

#[test]
fn every_node_source_file_is_declared_by_a_mod_line() {
    let nodes = root().join("nodes");
    let mut missing = Vec::new();
    for c in std::fs::read_dir(&nodes).unwrap() {
        let crate_dir = c.unwrap().path();
        if !crate_dir.join("Cargo.toml").exists() {
            continue;
        }
        let mut files = Vec::new();
        rust_files(&crate_dir, &mut files);
        let path_attrs: Vec<String> = files
            .iter()
            .flat_map(|f| {
                let t = std::fs::read_to_string(f).unwrap();
                t.lines()
                    .filter_map(|l| l.trim().strip_prefix("#[path = \""))
                    .filter_map(|r| r.split('"').next())
                    .map(String::from)
                    .collect::<Vec<_>>()
            })
            .collect();
        for f in files {
            if f.file_name().unwrap() == "lib.rs" {
                continue;
            }
            let (name, parents) = declarers(&f, &crate_dir);
            let fname = f.file_name().unwrap().to_string_lossy().into_owned();
            // Or a `#[path = "..."]` attribute anywhere in the crate naming it.
            let rel = f
                .strip_prefix(&crate_dir)
                .unwrap()
                .to_string_lossy()
                .replace('\\', "/");
            let by_path = path_attrs
                .iter()
                .any(|a| rel.ends_with(a.as_str()) || *a == fname);
            let declared = by_path
                || parents.iter().any(|p| {
                    std::fs::read_to_string(p).is_ok_and(|t| {
                        t.lines().any(|l| {
                            let l = l.trim();
                            l.ends_with(&format!("mod {name};")) && l.contains("mod ")
                        })
                    })
                });
            if !declared {
                missing.push(f.strip_prefix(&nodes).unwrap().display().to_string());
            }
        }
    }
    assert!(
        missing.is_empty(),
        "files under nodes/ that no `mod` line declares (they are not compiled): {missing:?}"
    );
}

#[test]
fn every_node_a_file_registers_is_in_the_builtin_registry() {
    let reg = cgnodes::nodes::builtin_registry();
    let mut files = Vec::new();
    rust_files(&root().join("nodes"), &mut files);
    let mut names = Vec::new();
    for f in &files {
        let text = std::fs::read_to_string(f).unwrap();
        // `r.add("name", ...)`, the name on the same line or the next.
        let mut rest = text.as_str();
        while let Some(i) = rest.find("r.add(") {
            rest = &rest[i + 6..];
            let arg = rest.trim_start();
            if let Some(body) = arg.strip_prefix('"') {
                let name = &body[..body.find('"').unwrap()];
                names.push((name.to_string(), f.clone()));
            }
        }
    }
    assert!(names.len() > 60, "found only {} registrations", names.len());
    let unregistered: Vec<String> = names
        .iter()
        .filter(|(n, _)| reg.get(n).is_none())
        .map(|(n, f)| format!("{n} ({})", f.display()))
        .collect();
    assert!(
        unregistered.is_empty(),
        "node types a file adds but the built-in registry lacks: {unregistered:?}"
    );
}
