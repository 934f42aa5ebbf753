//! The check that a crate's test suite lists every file.
//!
//! Each crate's integration tests are one test binary, `tests/suite/main.rs`,
//! with one module per file of `tests/suite/` (one link of the crate instead
//! of one per file: CI's disk filled while linking ~160 test binaries). Cargo
//! compiles only the modules that `main.rs` declares, so a file added beside
//! them and not declared would never compile or run, silently; this check
//! makes that a failing test.

use std::path::Path;

/// Panics, naming the file, if a `.rs` file of `<manifest_dir>/tests/suite`
/// other than `main.rs` has no `mod <stem>;` line in that folder's `main.rs`.
pub fn assert_lists_every_file(manifest_dir: &str) {
    let dir = Path::new(manifest_dir).join("tests/suite");
    let main = std::fs::read_to_string(dir.join("main.rs"))
        .unwrap_or_else(|e| panic!("reading {}/main.rs: {e}", dir.display()));
    let declared: Vec<&str> = main
        .lines()
        .filter_map(|l| l.trim().strip_prefix("mod ")?.strip_suffix(';'))
        .collect();
    let entries =
        std::fs::read_dir(&dir).unwrap_or_else(|e| panic!("listing {}: {e}", dir.display()));
    for entry in entries {
        let name = entry.expect("a directory entry").file_name();
        let name = name.to_string_lossy();
        if let Some(stem) = name.strip_suffix(".rs").filter(|s| *s != "main") {
            assert!(
                declared.contains(&stem),
                "{}/{name} is not declared in main.rs (`mod {stem};`)",
                dir.display()
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::assert_lists_every_file;

    /// A file beside the declared ones fails the check; declared, it passes.
    #[test]
    fn an_undeclared_file_is_named() {
        let root = std::env::temp_dir().join(format!("testkit-suite-{}", std::process::id()));
        let suite = root.join("tests/suite");
        std::fs::create_dir_all(&suite).unwrap();
        std::fs::write(suite.join("main.rs"), "mod a;\n").unwrap();
        std::fs::write(suite.join("a.rs"), "").unwrap();
        let dir = root.to_str().unwrap().to_owned();
        assert_lists_every_file(&dir);
        std::fs::write(suite.join("b.rs"), "").unwrap();
        let err = std::panic::catch_unwind(|| assert_lists_every_file(&dir)).unwrap_err();
        let msg = err.downcast_ref::<String>().cloned().unwrap_or_default();
        std::fs::remove_dir_all(&root).unwrap();
        assert!(msg.contains("b.rs is not declared"), "{msg}");
    }
}
