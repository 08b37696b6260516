//! The suite runs from a clone of the repository alone: no file under `crates/` (sources, tests, examples,
//! build scripts, manifests) names a path into a `shared` folder beside or above the repository. Extra scenes
//! reach benchmarks and measurements only through the `HRTAO_SHARED` environment variable.

use std::path::{Path, PathBuf};

fn files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            if path.file_name().is_some_and(|n| n != "target") {
                files(&path, out);
            }
        } else {
            out.push(path);
        }
    }
}

/// The offending lines of `text`, numbered from 1: each line naming `..` + `/shared` or `/shared` + `/`.
fn mentions(text: &str) -> Vec<(usize, &str)> {
    // Built at run time so that this file does not name them itself.
    let patterns = [["..", "/shared"].concat(), ["/shared", "/"].concat()];
    text.lines()
        .enumerate()
        .filter(|(_, line)| patterns.iter().any(|p| line.contains(p.as_str())))
        .map(|(i, line)| (i + 1, line.trim()))
        .collect()
}

#[test]
fn no_file_under_crates_names_a_shared_folder() {
    let crates = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut all = Vec::new();
    files(&crates, &mut all);
    let mut scanned = 0;
    let mut found = Vec::new();
    for path in &all {
        let Ok(text) = std::fs::read_to_string(path) else {
            continue; // not UTF-8 text (images, binaries)
        };
        scanned += 1;
        let rel = path
            .strip_prefix(&crates)
            .unwrap()
            .to_string_lossy()
            .replace('\\', "/");
        for (line, content) in mentions(&text) {
            found.push(format!("crates/{rel}:{line}: {content}"));
        }
    }
    // The scan saw the tree: this file, the crates' manifests and sources.
    assert!(
        scanned > 50,
        "only {scanned} text files under {}",
        crates.display()
    );
    assert!(all.iter().any(|p| p.ends_with("scene/tests/no_outside_paths.rs")));
    assert!(
        found.is_empty(),
        "paths outside the repository (tests read testdata/; benchmarks take HRTAO_SHARED):\n{}",
        found.join("\n")
    );
}

/// The scan finds what it looks for: both spellings, in code and in comments, with the line number.
#[test]
fn the_scan_finds_both_spellings() {
    let dot = ["..", "/shared"].concat();
    let abs = ["/work", "/shared", "/refs"].concat();
    let text = format!("fn a() {{}}\nlet p = \"{dot}/scenes\";\n// see {abs}\nlet q = \"shared_scene\";\n");
    let found = mentions(&text);
    assert_eq!(found.iter().map(|(l, _)| *l).collect::<Vec<_>>(), vec![2, 3]);
}
