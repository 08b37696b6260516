//! One truth for formats and environment variables: every extension of `hrtao_scene::SUPPORTED_EXTENSIONS` is in
//! each command's `--help`, packaging/hrtao-mime.xml (one MIME type per format, with a glob per extension), and
//! through those types in the desktop entry (with a keyword each), the thumbnailer and the AppStream metainfo, and
//! in docs/command-line.md and the README (the Open dialog's filter is tested in `view::files`). The environment variables of
//! `--help` (`cli::ENVIRONMENT`) are the rows of docs/command-line.md's table, word for word, and include every
//! variable the crates read. `hrtao generate-shell-files` writes completions and man pages.
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::process::Command;

fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").join(path)
}

fn read(path: &str) -> String {
    std::fs::read_to_string(repo(path)).unwrap_or_else(|e| panic!("{path}: {e}"))
}

fn hrtao(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_hrtao"))
        .args(args)
        .output()
        .expect("run hrtao");
    assert!(out.status.success(), "hrtao {args:?}: {out:?}");
    String::from_utf8(out.stdout).unwrap()
}

/// packaging/hrtao-mime.xml: each MIME type and the extensions of its globs (`*.ext`).
fn mime_xml() -> BTreeMap<String, Vec<String>> {
    let xml = read("packaging/hrtao-mime.xml");
    let mut types = BTreeMap::new();
    for block in xml.split("<mime-type type=\"").skip(1) {
        let (name, body) = block.split_once('"').unwrap();
        let body = body.split("</mime-type>").next().unwrap();
        let globs: Vec<String> = body
            .split("<glob pattern=\"*.")
            .skip(1)
            .map(|g| g.split('"').next().unwrap().to_string())
            .collect();
        assert!(!globs.is_empty(), "{name} has no glob");
        assert!(types.insert(name.to_string(), globs).is_none(), "{name} twice");
    }
    types
}

/// `KEY=` of a desktop-entry-style file, as a `;`-separated set.
fn list(text: &str, key: &str) -> BTreeSet<String> {
    let line = text
        .lines()
        .find_map(|l| l.strip_prefix(&format!("{key}=")))
        .unwrap_or_else(|| panic!("no {key}= in\n{text}"));
    assert!(line.ends_with(';'), "{key} is a ;-terminated list");
    line.split(';')
        .filter(|m| !m.is_empty())
        .map(str::to_string)
        .collect()
}

/// The words of a text, split at what is not part of an extension token (`.ext`).
fn tokens(text: &str) -> BTreeSet<String> {
    text.split(|c: char| !(c.is_ascii_alphanumeric() || c == '.'))
        .map(|t| t.trim_end_matches('.').to_ascii_lowercase())
        .collect()
}

#[test]
fn every_extension_is_in_the_help_the_packaging_and_the_docs() {
    let exts = hrtao_scene::SUPPORTED_EXTENSIONS;
    let types = mime_xml();
    // The MIME file: every extension under exactly one type, and nothing else.
    let globbed: Vec<&str> = types.values().flatten().map(String::as_str).collect();
    for ext in exts {
        assert_eq!(
            globbed.iter().filter(|g| **g == ext).count(),
            1,
            ".{ext}: one glob in packaging/hrtao-mime.xml"
        );
    }
    assert_eq!(globbed.len(), exts.len(), "globs of no format: {globbed:?}");
    let type_names: BTreeSet<String> = types.keys().cloned().collect();

    let desktop = read("packaging/hrtao.desktop");
    assert_eq!(list(&desktop, "MimeType"), type_names, "hrtao.desktop MimeType");
    let keywords: BTreeSet<String> = list(&desktop, "Keywords")
        .iter()
        .map(|k| k.to_ascii_lowercase())
        .collect();
    for ext in exts {
        assert!(keywords.contains(ext), "hrtao.desktop Keywords lacks {ext}");
    }
    let thumbnailer = read("packaging/hrtao.thumbnailer");
    assert_eq!(
        list(&thumbnailer, "MimeType"),
        type_names,
        "hrtao.thumbnailer MimeType"
    );
    let metainfo = read("packaging/io.github.hrtao.hrtao.metainfo.xml");
    let media: BTreeSet<String> = metainfo
        .split("<mediatype>")
        .skip(1)
        .map(|m| m.split('<').next().unwrap().to_string())
        .collect();
    assert_eq!(media, type_names, "the metainfo's mediatypes");

    let mut texts: Vec<(String, String)> = [
        &["--help"][..],
        &["view", "--help"],
        &["render", "--help"],
        &["bench", "--help"],
        &["thumbnail", "--help"],
    ]
    .iter()
    .map(|args| (format!("hrtao {}", args.join(" ")), hrtao(args)))
    .collect();
    for doc in ["docs/command-line.md", "README.md"] {
        texts.push((doc.into(), read(doc)));
    }
    for (name, text) in &texts {
        let words = tokens(text);
        let missing: Vec<&str> = exts
            .iter()
            .copied()
            .filter(|e| !words.contains(&format!(".{e}")))
            .collect();
        assert!(missing.is_empty(), "{name} lacks {missing:?}:\n{text}");
    }
}

/// The variables of `--help`'s Environment section: each `  NAME` line (names separated by ", ", each up to a `=`).
fn help_variables(help: &str) -> BTreeSet<String> {
    let section = help
        .split("\nEnvironment:\n")
        .nth(1)
        .expect("an Environment section");
    section
        .lines()
        .filter(|l| l.starts_with("  ") && !l.starts_with("   "))
        .map(|l| l.trim().to_string())
        .collect()
}

#[test]
fn environment_variables_are_one_list_in_the_help_and_the_docs() {
    let help = hrtao(&["--help"]);
    let named = help_variables(&help);
    // docs/command-line.md's table has one row per variable of the help, word for word: `| `NAME` | TEXT |`.
    let docs = read("docs/command-line.md");
    let table = docs
        .split("## Environment variables\n")
        .nth(1)
        .expect("docs/command-line.md: an Environment variables section");
    let rows: Vec<&str> = table
        .lines()
        .skip_while(|l| !l.starts_with('|'))
        .take_while(|l| l.starts_with('|'))
        .skip(2)
        .collect();
    let documented: BTreeSet<String> = rows
        .iter()
        .map(|r| {
            let cell = r.trim_start_matches("| `");
            cell.split("` |").next().unwrap().replace("\\|", "|")
        })
        .collect();
    assert_eq!(
        documented, named,
        "docs/command-line.md's table and `hrtao --help` (crates/viewer/src/cli.rs ENVIRONMENT)"
    );
    // The text too: the help's wrapped text of each variable is the row's, whitespace aside.
    let flat = |s: &str| s.split_whitespace().collect::<Vec<_>>().join(" ");
    let section = help.split("\nEnvironment:\n").nth(1).unwrap();
    let mut help_rows = Vec::new();
    for l in section.lines() {
        if l.starts_with("  ") && !l.starts_with("   ") {
            help_rows.push((l.trim().to_string(), String::new()));
        } else if let Some(last) = help_rows.last_mut() {
            last.1.push(' ');
            last.1.push_str(l.trim());
        }
    }
    for (name, text) in &help_rows {
        let row = format!(
            "| `{}` | {} |",
            name.replace('|', "\\|"),
            flat(text).replace('|', "\\|")
        );
        assert!(
            rows.iter().any(|r| flat(r) == row),
            "docs/command-line.md has no row\n{row}\n(the table, from cli.rs ENVIRONMENT:)\n{}",
            help_rows
                .iter()
                .map(|(n, t)| format!(
                    "| `{}` | {} |",
                    n.replace('|', "\\|"),
                    flat(t).replace('|', "\\|")
                ))
                .collect::<Vec<_>>()
                .join("\n")
        );
    }
    // Every variable the crates read (std::env::var/var_os("NAME"), clap's `env = "NAME"`) is listed.
    let listed: BTreeSet<String> = named
        .iter()
        .flat_map(|n| n.split(", "))
        .map(|n| n.split('=').next().unwrap().to_string())
        .collect();
    let mut read_vars = BTreeSet::new();
    let mut stack = vec![repo("crates")];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            let name = path.file_name().unwrap().to_string_lossy().to_string();
            if path.is_dir() {
                if !["tests", "target", "benches"].contains(&name.as_str()) {
                    stack.push(path);
                }
            } else if name.ends_with(".rs") && name != "build.rs" {
                let text = std::fs::read_to_string(&path).unwrap();
                for pat in ["env::var(\"", "env::var_os(\"", ", env = \""] {
                    for part in text.split(pat).skip(1) {
                        read_vars.insert(part.split('"').next().unwrap().to_string());
                    }
                }
            }
        }
    }
    // The process's own and the build's.
    for own in ["HOME", "CARGO_MANIFEST_DIR", "OUT_DIR"] {
        read_vars.remove(own);
    }
    let unlisted: Vec<&String> = read_vars.difference(&listed).collect();
    assert!(
        unlisted.is_empty(),
        "read but not in `hrtao --help` (cli.rs ENVIRONMENT): {unlisted:?}"
    );
}

#[test]
fn completions_and_man_pages_are_generated() {
    let dir = std::env::temp_dir().join(format!("hrtao-shell-files-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    hrtao(&["generate-shell-files", dir.to_str().unwrap()]);
    let bash = std::fs::read_to_string(dir.join("hrtao.bash")).unwrap();
    for w in ["thumbnail", "--max-file-mb", "render", "--ray-backend"] {
        assert!(bash.contains(w), "the bash completion lacks {w}");
    }
    let zsh = std::fs::read_to_string(dir.join("_hrtao")).unwrap();
    assert!(zsh.starts_with("#compdef hrtao"), "{}", &zsh[..80]);
    let fish = std::fs::read_to_string(dir.join("hrtao.fish")).unwrap();
    assert!(fish.contains("complete -c hrtao"));
    let man = std::fs::read_to_string(dir.join("man1/hrtao.1")).unwrap();
    assert!(man.contains(".TH hrtao 1"), "{}", &man[..200]);
    for page in ["view", "render", "bench", "devices", "thumbnail"] {
        let p = dir.join(format!("man1/hrtao-{page}.1"));
        assert!(p.is_file(), "{} missing", p.display());
    }
    assert!(!dir.join("man1/hrtao-generate-shell-files.1").exists());
    // Syntax, where the shells are installed.
    for (shell, file, check) in [
        ("bash", "hrtao.bash", "-n"),
        ("zsh", "_hrtao", "-n"),
        ("fish", "hrtao.fish", "--no-execute"),
    ] {
        match Command::new(shell).arg(check).arg(dir.join(file)).output() {
            Ok(o) => assert!(o.status.success(), "{shell} {check} {file}: {o:?}"),
            Err(_) => println!("{shell} is not installed: its completion's syntax is not checked"),
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
