//! The command line's own help: exit codes and examples in `--help`, and shell completion
//! scripts that the shell accepts.

use std::process::Command;

fn cgnodes(args: &[&str]) -> (bool, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_cgnodes"))
        .args(args)
        .output()
        .unwrap();
    (
        o.status.success(),
        String::from_utf8_lossy(&o.stdout).into_owned(),
    )
}

#[test]
fn help_lists_exit_codes_and_each_subcommand_has_an_example() {
    let (ok, help) = cgnodes(&["--help"]);
    assert!(ok);
    for code in ["Exit codes:", "  1 ", "  2 ", "  3 ", "  130 "] {
        assert!(help.contains(code), "--help lacks {code:?}:\n{help}");
    }
    for sub in [
        "run",
        "validate",
        "nodes",
        "describe",
        "schema",
        "dot",
        "sweep",
        "sweep-merge",
        "chart",
        "import-f3d",
        "f3d-project",
        "completions",
    ] {
        let (ok, h) = cgnodes(&[sub, "--help"]);
        assert!(ok, "{sub} --help failed");
        assert!(
            h.contains(&format!("Example: cgnodes {sub}")),
            "{sub} --help has no example:\n{h}"
        );
    }
}

#[test]
fn completion_scripts_parse_in_their_shell() {
    let (ok, bash) = cgnodes(&["completions", "bash"]);
    assert!(ok);
    for word in ["sweep-merge", "--frames", "--plugins"] {
        assert!(bash.contains(word), "bash completions lack {word}");
    }
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("cgnodes.bash");
    std::fs::write(&f, &bash).unwrap();
    // `bash -n` parses without running
    let st = Command::new("bash").arg("-n").arg(&f).status().unwrap();
    assert!(st.success(), "bash rejects the completion script");
    let (ok, fish) = cgnodes(&["completions", "fish"]);
    assert!(ok && fish.contains("complete -c cgnodes"));
    let (ok, _) = cgnodes(&["completions", "tcsh"]);
    assert!(!ok, "an unknown shell is refused");
}
