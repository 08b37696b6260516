//! Where a young map's additions live (`crate::additions`, docs/architecture.md "Where an addition goes"): each
//! is named, in the renderer's source and shaders, only by its settings group, its own Rust file and the
//! additions' list (`additions/mod.rs`), the pass list (`passes.rs`), the buffers and GPU constants (`pass.rs`'s
//! `Resource`, `gpu_types.rs`), its own shader files (`shaders/NAME.glsl`, `shaders/NAME.comp`) and the shaders
//! that include its file (the pass it changes). So adding or deleting one touches those, its test and its docs, never the renderer, the hash
//! map or another addition. A name is the setting's field as a whole word (`near_field`), or its type or
//! constant form inside any identifier (`NearField`, `NEAR_FIELD`: `FLAG_NEAR_FIELD`, `ContactDetailRef`). The
//! viewer, which offers the settings by name, and the tests are not checked.
use std::path::{Path, PathBuf};

use hrtao_core::settings::YoungMapSettings;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Every file under `dir` (recursively) with one of `exts`, as (path relative to the root, text).
fn files(dir: &Path, exts: &[&str], out: &mut Vec<(String, String)>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            files(&path, exts, out);
        } else if exts.iter().any(|e| path.extension().is_some_and(|x| x == *e)) {
            let rel = path
                .strip_prefix(root())
                .unwrap()
                .to_string_lossy()
                .replace('\\', "/");
            out.push((rel, std::fs::read_to_string(&path).unwrap()));
        }
    }
}

/// Whether `text` holds `word` with no identifier character on either side.
fn names(text: &str, word: &str) -> bool {
    let ident = |c: char| c.is_ascii_alphanumeric() || c == '_';
    text.match_indices(word).any(|(i, _)| {
        let before = text[..i].chars().next_back();
        let after = text[i + word.len()..].chars().next();
        !before.is_some_and(ident) && !after.is_some_and(ident)
    })
}

/// Whether `text` names addition `name` (snake case): the word itself, or its CamelCase or UPPER_CASE form
/// anywhere.
fn names_addition(text: &str, name: &str) -> bool {
    let camel: String = name
        .split('_')
        .map(|w| {
            let mut c = w.chars();
            c.next()
                .map_or(String::new(), |f| f.to_ascii_uppercase().to_string() + c.as_str())
        })
        .collect();
    names(text, name) || text.contains(&camel) || text.contains(&name.to_ascii_uppercase())
}

/// The files that may name addition `name`.
fn allowed(name: &str, sources: &[(String, String)]) -> Vec<String> {
    let mut ok: Vec<String> = [
        "crates/hrtao-core/src/settings/young.rs",
        "crates/hrtao-core/src/settings/mod.rs",
        "crates/hrtao-core/src/additions/mod.rs",
        "crates/hrtao-core/src/passes.rs",
        "crates/hrtao-core/src/pass.rs",
        "crates/hrtao-core/src/gpu_types.rs",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    ok.push(format!("crates/hrtao-core/src/additions/{name}.rs"));
    ok.push(format!("shaders/{name}.glsl"));
    ok.push(format!("shaders/{name}.comp"));
    let include = format!("#include \"{name}.glsl\"");
    ok.extend(
        sources
            .iter()
            .filter(|(path, text)| path.starts_with("shaders/") && text.contains(&include))
            .map(|(path, _)| path.clone()),
    );
    ok
}

#[test]
fn each_young_map_addition_is_named_only_by_its_own_files_and_the_lists() {
    let mut sources = Vec::new();
    files(&root().join("crates/hrtao-core/src"), &["rs"], &mut sources);
    files(
        &root().join("shaders"),
        &["glsl", "comp", "vert", "frag"],
        &mut sources,
    );
    assert!(
        sources.iter().any(|(p, _)| p.ends_with("renderer.rs")),
        "sources found"
    );
    let mut wrong = Vec::new();
    for (name, _) in YoungMapSettings::CLASSES {
        let ok = allowed(name, &sources);
        assert!(
            sources
                .iter()
                .any(|(p, _)| *p == format!("crates/hrtao-core/src/additions/{name}.rs")),
            "{name} has its file in additions/"
        );
        assert!(
            sources.iter().any(|(p, _)| *p == format!("shaders/{name}.glsl")),
            "{name} has its shader file"
        );
        for (path, text) in &sources {
            if names_addition(text, name) && !ok.contains(path) {
                wrong.push(format!("{path} names {name}"));
            }
        }
    }
    assert!(
        wrong.is_empty(),
        "files outside an addition's own name it:\n{}",
        wrong.join("\n")
    );
}

#[test]
fn names_of_an_addition() {
    assert!(names_addition("if (s.young.near_field) {", "near_field"));
    assert!(names_addition("#include \"near_field.glsl\"", "near_field"));
    assert!(names_addition("g.flags |= gpu::FLAG_NEAR_FIELD;", "near_field"));
    assert!(names_addition("Resource::ContactDetail", "contact_detail"));
    assert!(!names_addition("near_field_on()", "near_field"));
    assert!(!names_addition("the near field", "near_field"));
}
