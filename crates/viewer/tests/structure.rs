//! Guards on the viewer's structure (issue #61), read from the source text so that it does not erode again:
//! `Viewer` has at most 25 fields, nothing but view/mod.rs implements it, view/mod.rs stays within 900 lines,
//! and `Viewer::draw` and its successor in the frame loop (`FrameLoop::record`) within 80 each. Each check is
//! also run on a mutated copy of the source (a field added, an `impl Viewer` elsewhere, …), which it must reject.
use std::path::{Path, PathBuf};

const MAX_FIELDS: usize = 25;
const MAX_MOD_LINES: usize = 900;
const MAX_DRAW_LINES: usize = 80;

fn src() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Every `.rs` file under `dir`, sorted.
fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display())) {
        let path = entry.unwrap().path();
        if path.is_dir() {
            out.extend(rust_files(&path));
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
    out.sort();
    out
}

/// The lines of `text` from the one that opens `opening` (a line starting with it, after indentation) to the
/// line that closes it at the same indentation.
fn block<'a>(text: &'a str, opening: &str) -> Option<Vec<&'a str>> {
    let lines: Vec<&str> = text.lines().collect();
    let start = lines.iter().position(|l| l.trim_start().starts_with(opening))?;
    let indent = lines[start].len() - lines[start].trim_start().len();
    let close = format!("{}}}", " ".repeat(indent));
    let end = lines[start..]
        .iter()
        .position(|l| l.starts_with(&close) && l.trim() == "}")?;
    Some(lines[start..=start + end].to_vec())
}

/// The number of fields of `struct Viewer` in `text` (view/mod.rs): the lines `name: Type,` at its top level.
fn viewer_fields(text: &str) -> Result<usize, String> {
    let opening = [
        "pub(crate) struct Viewer {",
        "pub struct Viewer {",
        "struct Viewer {",
    ]
    .iter()
    .find_map(|o| block(text, o))
    .ok_or("no `struct Viewer {` in view/mod.rs")?;
    let body = &opening[1..opening.len() - 1];
    let indent = body
        .iter()
        .find(|l| !l.trim().is_empty())
        .map_or(4, |l| l.len() - l.trim_start().len());
    let is_field = |l: &&&str| {
        let at_top = l.len() - l.trim_start().len() == indent;
        let t = l.trim_start();
        let t = t
            .strip_prefix("pub(crate) ")
            .or(t.strip_prefix("pub(super) "))
            .or(t.strip_prefix("pub "))
            .unwrap_or(t);
        let name: String = t
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        at_top && !name.is_empty() && t[name.len()..].starts_with(':') && !t.starts_with("//")
    };
    let n = body.iter().filter(is_field).count();
    if n > MAX_FIELDS {
        return Err(format!(
            "`Viewer` has {n} fields, more than {MAX_FIELDS}: group what belongs together in a struct of its own \
             (as `FrameLoop`, `Script`, `Reload` do) instead of adding fields to the viewer"
        ));
    }
    Ok(n)
}

/// Whether a line implements something for `Viewer` (`impl Viewer`, `impl super::Viewer`, `impl X for Viewer`).
fn implements_viewer(line: &str) -> bool {
    let t = line.trim_start();
    let Some(rest) = t.strip_prefix("impl") else {
        return false;
    };
    if !(rest.starts_with(' ') || rest.starts_with('<')) {
        return false;
    }
    // The implementing type: after ` for ` if there is one, else the first path after `impl` (and its generics).
    let head = rest.split('{').next().unwrap_or(rest);
    let ty = match head.rsplit_once(" for ") {
        Some((_, ty)) => ty,
        None => {
            let h = head.trim_start();
            match h.strip_prefix('<') {
                Some(g) => g.split_once('>').map_or("", |(_, t)| t),
                None => h,
            }
        }
    };
    let ty = ty.split(['<', ' ', '\t']).find(|s| !s.is_empty()).unwrap_or("");
    ty.rsplit("::").next() == Some("Viewer")
}

/// The files (relative to src/) other than view/mod.rs that implement `Viewer`, with the line.
fn viewer_impls_outside(files: &[(String, String)]) -> Vec<String> {
    let mut out = Vec::new();
    for (name, text) in files {
        if name == "view/mod.rs" {
            continue;
        }
        for (i, line) in text.lines().enumerate() {
            if implements_viewer(line) {
                out.push(format!("{name}:{}: {}", i + 1, line.trim()));
            }
        }
    }
    out
}

/// The viewer's sources, as (path relative to src/, text).
fn sources() -> Vec<(String, String)> {
    let root = src();
    rust_files(&root)
        .into_iter()
        .map(|p| {
            let name = p
                .strip_prefix(&root)
                .unwrap()
                .to_string_lossy()
                .replace('\\', "/");
            (name, read(&p))
        })
        .collect()
}

fn view_mod() -> String {
    read(&src().join("view/mod.rs"))
}

#[test]
fn the_viewer_has_at_most_25_fields() {
    let text = view_mod();
    let n = viewer_fields(&text).unwrap_or_else(|e| panic!("{e}"));
    assert!(
        n >= 10,
        "only {n} fields counted in `struct Viewer`: is the count still right?"
    );
    // Mutation: as many fields added as it takes to pass the limit, and the guard fails.
    let extra: String = (0..=MAX_FIELDS - n)
        .map(|k| format!("    extra_{k}: u32,\n"))
        .collect();
    let mutated = text.replacen(
        "    scene: Option<Scene>,\n",
        &format!("    scene: Option<Scene>,\n{extra}"),
        1,
    );
    assert_ne!(
        mutated, text,
        "the mutation found no `scene` field to add fields beside"
    );
    let err = viewer_fields(&mutated).expect_err("a viewer with more than 25 fields passes the guard");
    assert!(err.contains(&format!("{} fields", MAX_FIELDS + 1)), "{err}");
    // A nested struct's fields and comments are not the viewer's.
    let nested = "struct Viewer {\n    a: u32,\n    // b: u32,\n    /// c: u32\n    d: Vec<u32>,\n}\n";
    assert_eq!(viewer_fields(nested), Ok(2));
}

#[test]
fn only_view_mod_implements_the_viewer() {
    let files = sources();
    assert!(
        files
            .iter()
            .any(|(n, t)| n == "view/mod.rs" && t.lines().any(implements_viewer)),
        "view/mod.rs has no `impl Viewer`: is the check still right?"
    );
    let outside = viewer_impls_outside(&files);
    assert!(
        outside.is_empty(),
        "`Viewer` is implemented outside view/mod.rs (take what the code reads as arguments and return commands \
         or events, as view/script.rs and view/frame_loop.rs do):\n{}",
        outside.join("\n")
    );
    // Mutation: each spelling of an implementation elsewhere is found.
    for line in [
        "impl Viewer {",
        "impl super::Viewer {",
        "impl crate::view::Viewer {",
        "impl Drop for Viewer {",
        "impl<'a> From<&'a str> for super::Viewer {",
    ] {
        let mutated = vec![("view/reload.rs".to_string(), format!("use x;\n{line}\n}}\n"))];
        assert_eq!(viewer_impls_outside(&mutated).len(), 1, "{line}");
    }
    for line in [
        "impl ViewerLike {",
        "impl Viewer2 for App {",
        "// impl Viewer {",
        "impl ApplicationHandler<Wake> for App {",
    ] {
        assert!(!implements_viewer(line), "{line}");
    }
}

#[test]
fn view_mod_and_draw_stay_small() {
    let text = view_mod();
    let lines = text.lines().count();
    assert!(
        lines <= MAX_MOD_LINES,
        "view/mod.rs has {lines} lines, more than {MAX_MOD_LINES}: the viewer applies commands and events; the \
         work goes in the modules beside it"
    );
    let draw = block(&text, "fn draw(").expect("`fn draw(` in view/mod.rs");
    assert!(
        draw.len() <= MAX_DRAW_LINES,
        "`Viewer::draw` has {} lines, more than {MAX_DRAW_LINES} (the frame's work is view/frame_loop.rs's)",
        draw.len()
    );
    // Its successor in the frame loop: the frame's plan, recording, submission and presentation.
    let frame_loop = read(&src().join("view/frame_loop.rs"));
    let record = block(&frame_loop, "pub fn record(").expect("`pub fn record(` in view/frame_loop.rs");
    assert!(
        record.len() <= MAX_DRAW_LINES,
        "`FrameLoop::record` has {} lines, more than {MAX_DRAW_LINES}",
        record.len()
    );
}
