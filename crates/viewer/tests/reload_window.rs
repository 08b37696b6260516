//! Recent files and reload on change, driven with real X input under Xvfb (xdotool): the Recent menu opens a
//! file remembered in the preferences, a rewrite of the open file on disk reloads it with the camera kept (the
//! screenshot shows the new model), F5 reloads by hand, and a broken rewrite keeps the old model on screen with
//! the error in a toast.
mod common;

use std::path::{Path, PathBuf};
use std::time::Duration;

use common::{differing_pixels, display_available, out_dir, write_box_stl, x_input_lock, xdotool, Running};

/// Pixels of the screenshot that differ from the background, a vertical gradient: each row's first pixel (the
/// model must not touch the view's left edge).
fn covered_pixels(png: &Path) -> usize {
    let img = image::open(png).unwrap().to_rgb8();
    img.enumerate_pixels()
        .filter(|(_, y, p)| {
            let bg = img.get_pixel(0, *y);
            p.0.iter().zip(bg.0).any(|(a, b)| a.abs_diff(b) > 24)
        })
        .count()
}

/// Writes `path` the way an exporter does: a temporary file beside it, renamed over it (a new inode).
fn save_by_rename(path: &Path, write: impl FnOnce(&Path)) {
    let tmp = path.with_extension("stl.part");
    write(&tmp);
    std::fs::rename(&tmp, path).unwrap();
}

#[test]
fn recent_files_and_reload_on_change_keep_the_view() {
    if !display_available() {
        return;
    }
    let _x = x_input_lock();
    let dir = out_dir("reload");
    // Two boxes: a cube and a box twice as wide and deep.
    let (small, wide) = (dir.join("small.stl"), dir.join("wide.stl"));
    write_box_stl(&small, [-0.5, -0.5, 0.0], [0.5, 0.5, 1.0]);
    write_box_stl(&wide, [-1.0, -1.0, 0.0], [1.0, 1.0, 1.0]);
    let wide_abs = std::fs::canonicalize(&wide).unwrap();
    // The preferences remember `wide` from an earlier run.
    let config = dir.join("viewer.json");
    std::fs::write(
        &config,
        serde_json::json!({ "recent": [wide_abs], "auto_reload": true }).to_string(),
    )
    .unwrap();

    let mut v = Running::start_with(
        &[
            small.to_str().unwrap(),
            "--size",
            "900x600",
            "--config",
            config.to_str().unwrap(),
        ],
        &dir,
        &[("HRTAO_UI_PROBE", Some("1"))],
    );
    v.wait_for("] opened ", 1, Duration::from_secs(120));
    let window = v.focus_window();
    let first = v.screenshot(&window, &dir, 1);
    let (w, h) = image::image_dimensions(&first).unwrap();
    let area = (w * h) as usize;

    // File ▸ Recent: `small` went to the front, `wide` is second.
    let menu = v.probed("recent");
    v.click_until(&window, menu, "ui probe: recent 2 at ", 1);
    let entry = v.probed("recent 2");
    v.click_until(&window, entry, "] opened ", 2);
    assert!(v.log_text().contains("wide.stl"), "{}", v.log_text());
    let saved: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&config).unwrap()).unwrap();
    let recent: Vec<PathBuf> = serde_json::from_value(saved["recent"].clone()).unwrap();
    assert_eq!(
        recent,
        vec![wide_abs.clone(), std::fs::canonicalize(&small).unwrap()],
        "most recent first, saved at once"
    );
    let second = v.screenshot(&window, &dir, 2);
    let changed = differing_pixels(&first, &second, 24);
    assert!(
        changed * 20 > area,
        "the wide box shows: {changed} of {area} pixels differ from the cube's view"
    );

    // Re-exported on disk as a small block in one corner: reloaded by itself with the camera kept, so the
    // block covers a fraction of the view (a view framed on it would fill most of the view, as the boxes did).
    save_by_rename(&wide, |p| write_box_stl(p, [-1.0, -1.0, 0.0], [-0.5, -0.5, 0.5]));
    v.wait_for("] Reloaded wide.stl", 1, Duration::from_secs(60));
    let third = v.screenshot(&window, &dir, 3);
    let block_px = covered_pixels(&third);
    assert!(
        block_px > 1000 && block_px * 5 < area,
        "the block ({block_px} of {area} pixels) in the view of the wide box"
    );

    // F5 reloads by hand.
    xdotool(&["key", "--window", &window, "F5"]);
    v.wait_for("] Reloaded wide.stl", 2, Duration::from_secs(60));

    // A broken rewrite (a binary STL that promises 1000 triangles and holds none): the old model stays.
    save_by_rename(&wide, |p| {
        let mut bytes = vec![0u8; 80];
        bytes.extend_from_slice(&1000u32.to_le_bytes());
        std::fs::write(p, bytes).unwrap();
    });
    v.wait_for(
        "reload failed, the previous model stays",
        1,
        Duration::from_secs(60),
    );
    v.wait_for("ui probe: toast = reload failed", 1, Duration::from_secs(30));
    let fourth = v.screenshot(&window, &dir, 4);
    let kept_px = covered_pixels(&fourth);
    assert!(
        kept_px.abs_diff(block_px) * 10 < block_px,
        "the block stays on screen: {kept_px} pixels against {block_px}"
    );
    // Fixed again: it comes back by itself.
    save_by_rename(&wide, |p| write_box_stl(p, [-1.0, -1.0, 0.0], [1.0, 1.0, 1.0]));
    v.wait_for("] Reloaded wide.stl", 3, Duration::from_secs(60));
    v.validation_clean();
    let _ = std::fs::remove_dir_all(dir);
}
