//! packaging/hrtao.desktop: a valid desktop entry (desktop-file-validate too where it is installed) that launches
//! `hrtao FILE`, names the icon beside it and the window's application id, and offers exactly the formats the
//! loaders read. packaging/install.sh installs it with the MIME types, the thumbnailer, the metainfo (valid for
//! appstreamcli where it is installed), the completions and the man pages, and the MIME database it updates
//! gives every extension its type.
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

/// The MIME type of each extension: packaging/hrtao-mime.xml's (which install.sh installs for the desktops that
/// lack some of them).
fn mime_of(ext: &str) -> String {
    let xml = std::fs::read_to_string(packaging().join("hrtao-mime.xml")).unwrap();
    xml.split("<mime-type type=\"")
        .skip(1)
        .find(|block| block.contains(&format!("<glob pattern=\"*.{ext}\"/>")))
        .and_then(|block| block.split('"').next())
        .unwrap_or_else(|| panic!("no MIME type for .{ext} in packaging/hrtao-mime.xml: add one"))
        .to_string()
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
    assert_eq!(
        exts,
        hrtao_scene::SUPPORTED_EXTENSIONS.into_iter().collect(),
        "the loaders dispatch on exactly SUPPORTED_EXTENSIONS"
    );
    let read: BTreeSet<String> = exts.iter().map(|e| mime_of(e)).collect();
    let missing: Vec<&String> = read.difference(&offered).collect();
    assert!(missing.is_empty(), "read but not offered: {missing:?}");
    let extra: Vec<&String> = offered.difference(&read).collect();
    assert!(extra.is_empty(), "offered but not read: {extra:?}");
}

/// `packaging/install.sh` with PREFIX in a temporary folder and HRTAO_BIN the binary under test: every file in its
/// place, the thumbnailer naming the binary by its absolute path, and (where update-mime-database is installed)
/// the MIME database built from hrtao-mime.xml maps each extension to its type.
#[test]
fn install_sh_installs_the_desktop_files_completions_and_man_pages() {
    let prefix = std::env::temp_dir().join(format!("hrtao-install-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&prefix);
    let out = std::process::Command::new("bash")
        .arg(packaging().join("install.sh"))
        .env("PREFIX", &prefix)
        .env("HRTAO_BIN", env!("CARGO_BIN_EXE_hrtao"))
        .output()
        .unwrap();
    let said = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.status.success(), "{said}");
    let share = prefix.join("share");
    for f in [
        "applications/hrtao.desktop",
        "icons/hicolor/scalable/apps/hrtao.svg",
        "mime/packages/hrtao.xml",
        "metainfo/io.github.hrtao.hrtao.metainfo.xml",
        "thumbnailers/hrtao.thumbnailer",
        "bash-completion/completions/hrtao",
        "zsh/site-functions/_hrtao",
        "fish/vendor_completions.d/hrtao.fish",
        "man/man1/hrtao.1",
        "man/man1/hrtao-thumbnail.1",
    ] {
        assert!(share.join(f).is_file(), "{f} not installed: {said}");
    }
    let bin = std::fs::canonicalize(env!("CARGO_BIN_EXE_hrtao")).unwrap();
    let thumbnailer = std::fs::read_to_string(share.join("thumbnailers/hrtao.thumbnailer")).unwrap();
    assert!(
        thumbnailer.contains(&format!("Exec={} thumbnail --size %s %i %o", bin.display()))
            && thumbnailer.contains(&format!("TryExec={}", bin.display())),
        "{thumbnailer}"
    );
    match std::fs::read_to_string(share.join("mime/globs2")) {
        Ok(globs) => {
            for ext in hrtao_scene::SUPPORTED_EXTENSIONS {
                let line = format!(":{}:*.{ext}", mime_of(ext));
                assert!(
                    globs.lines().any(|l| l.ends_with(&line)),
                    "no `{line}` in globs2:\n{globs}"
                );
            }
        }
        Err(_) => println!("update-mime-database is not installed: the MIME database is not checked"),
    }
    match std::process::Command::new("appstreamcli")
        .args(["validate", "--no-net"])
        .arg(share.join("metainfo/io.github.hrtao.hrtao.metainfo.xml"))
        .output()
    {
        Ok(o) => assert!(
            o.status.success(),
            "appstreamcli validate: {}{}",
            String::from_utf8_lossy(&o.stdout),
            String::from_utf8_lossy(&o.stderr)
        ),
        Err(_) => println!("appstreamcli is not installed: the metainfo is not validated"),
    }
    std::fs::remove_dir_all(&prefix).unwrap();
}
