//! packaging/hrtao.desktop: a valid desktop entry (desktop-file-validate too where it is installed) that launches
//! `hrtao FILE`, names the icon beside it and the window's application id, and offers exactly the formats the
//! loaders read.
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

fn packaging() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../packaging")
}

/// The entry's keys (each at most once) under its one group.
fn entry() -> BTreeMap<String, String> {
    let text = std::fs::read_to_string(packaging().join("hrtao.desktop")).unwrap();
    let mut lines = text
        .lines()
        .filter(|l| !l.trim().is_empty() && !l.starts_with('#'));
    assert_eq!(lines.next(), Some("[Desktop Entry]"));
    let mut keys = BTreeMap::new();
    for l in lines {
        assert!(!l.starts_with('['), "one group only: {l}");
        let (k, v) = l.split_once('=').unwrap_or_else(|| panic!("not KEY=VALUE: {l}"));
        assert!(
            k.chars().all(|c| c.is_ascii_alphanumeric() || c == '-'),
            "key {k:?}"
        );
        assert!(keys.insert(k.to_string(), v.to_string()).is_none(), "{k} twice");
    }
    keys
}

/// File extensions `hrtao_scene::load` dispatches on: the load of a missing file fails on the file, not with
/// "unsupported format".
fn loader_extensions() -> BTreeSet<&'static str> {
    let candidates = [
        "gltf", "glb", "obj", "stl", "ply", "step", "stp", "iges", "igs", "fbx", "dae", "3mf", "usd", "usdz",
        "3ds", "off", "x3d", "wrl", "dxf", "ifc", "blend",
    ];
    candidates
        .into_iter()
        .filter(|ext| {
            let path = format!("/nonexistent-hrtao-dir/model.{ext}");
            !matches!(
                hrtao_scene::load(&path, &mut |_| {}),
                Err(hrtao_scene::SceneError::UnsupportedFormat(_))
            )
        })
        .collect()
}

/// The MIME type a file manager gives each extension (shared-mime-info / IANA names).
fn mime_of(ext: &str) -> &'static str {
    match ext {
        "gltf" => "model/gltf+json",
        "glb" => "model/gltf-binary",
        "obj" => "model/obj",
        "stl" => "model/stl",
        "ply" => "application/x-ply",
        "3mf" => "model/3mf",
        "step" | "stp" => "model/step",
        "iges" | "igs" => "model/iges",
        // No registered type: the name FreeCAD and file managers give .ifc.
        "ifc" => "application/x-extension-ifc",
        other => panic!("no MIME type known for .{other}: add it here and to packaging/hrtao.desktop"),
    }
}

#[test]
fn desktop_entry_launches_hrtao_with_its_icon_and_application_id() {
    let e = entry();
    for (k, v) in [
        ("Type", "Application"),
        ("Name", "hrtao"),
        ("Exec", "hrtao %f"),
        ("Icon", "hrtao"),
        ("Terminal", "false"),
        ("StartupWMClass", "hrtao"),
    ] {
        assert_eq!(e.get(k).map(String::as_str), Some(v), "{k}");
    }
    for list in ["Categories", "MimeType", "Keywords"] {
        assert!(e[list].ends_with(';'), "{list} is a ;-terminated list");
    }
    assert!(
        e["Categories"].split(';').any(|c| c == "Graphics"),
        "a main category"
    );
    // The icon the entry names is ours, beside it.
    let svg = std::fs::read_to_string(packaging().join("hrtao.svg")).unwrap();
    assert!(
        svg.contains("<svg") && svg.contains("viewBox=\"0 0 128 128\""),
        "{svg}"
    );
    // The window's application id (Wayland app_id, X11 WM_CLASS) is the entry's name.
    let viewer =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("src/view/mod.rs")).unwrap();
    assert!(viewer.contains("pub const APP_ID: &str = \"hrtao\";"));
    // desktop-file-validate (desktop-file-utils, installed by scripts/install-deps.sh): no error, no warning.
    let out = std::process::Command::new("desktop-file-validate")
        .arg(packaging().join("hrtao.desktop"))
        .output()
        .expect("desktop-file-validate (run scripts/install-deps.sh)");
    let said = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.status.success() && said.trim().is_empty(), "{said}");
}

#[test]
fn desktop_entry_offers_exactly_the_formats_the_loaders_read() {
    let offered: BTreeSet<String> = entry()["MimeType"]
        .split(';')
        .filter(|m| !m.is_empty())
        .map(str::to_string)
        .collect();
    let exts = loader_extensions();
    for must in ["gltf", "glb", "obj", "stl", "ply", "step", "stp", "iges", "igs"] {
        assert!(
            exts.contains(must),
            "the probe finds the .{must} loader: {exts:?}"
        );
    }
    let read: BTreeSet<String> = exts.iter().map(|e| mime_of(e).to_string()).collect();
    let missing: Vec<&String> = read.difference(&offered).collect();
    assert!(missing.is_empty(), "read but not offered: {missing:?}");
    let extra: Vec<&String> = offered.difference(&read).collect();
    assert!(extra.is_empty(), "offered but not read: {extra:?}");
}
