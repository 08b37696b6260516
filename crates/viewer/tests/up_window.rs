//! The panel's up axis, driven with real X input under Xvfb (xdotool): a Y-up box opened in the viewer is turned
//! to +Z up from the Scene section's list, the view turns (pixels change), and when the same file is opened again
//! by a new viewer with the same preferences, it opens +Z up and shows the turned view.
mod common;

use std::time::Duration;

use common::{differing_pixels, display_available, out_dir, write_box_stl, x_input_lock, Running};

#[test]
fn an_up_axis_chosen_in_the_panel_is_used_when_the_file_opens_again() {
    if !display_available() {
        return;
    }
    let _x = x_input_lock();
    let dir = out_dir("up-window");
    // A tall box (y is 3x the others) beside a flat slab: which way is up shows.
    let model = dir.join("tower.stl");
    write_box_stl(&model, [0.0, 0.0, 0.0], [1.0, 3.0, 1.0]);
    let config = dir.join("viewer.json");
    let _ = std::fs::remove_file(&config);
    let args = [
        "--size",
        "720x450",
        "--config",
        config.to_str().unwrap(),
        model.to_str().unwrap(),
    ];
    let probe = [("HRTAO_UI_PROBE", Some("1"))];
    let mut v = Running::start_with(&args, &dir, &probe);
    v.wait_for("] opened ", 1, Duration::from_secs(120));
    v.wait_for("ui probe: up axis = +Y", 1, Duration::from_secs(60));
    let window = v.focus_window();
    std::thread::sleep(Duration::from_secs(2));
    let y_up = v.screenshot(&window, &dir, 1);
    let combo = v.probed("up axis");
    v.click_until(&window, combo, "ui probe: up axis +Z at", 1);
    let item = v.probed("up axis +Z");
    v.click_until(&window, item, "ui probe: up axis = +Z", 1);
    v.wait_for("up axis: +Z for ", 1, Duration::from_secs(10));
    std::thread::sleep(Duration::from_secs(2));
    let z_up = v.screenshot(&window, &dir, 2);
    let turned = differing_pixels(&y_up, &z_up, 12);
    assert!(turned > 2000, "choosing +Z changed {turned} pixels");
    v.validation_clean();
    drop(v);
    let saved = std::fs::read_to_string(&config).unwrap();
    assert!(saved.contains("\"up_axes\""), "{saved}");

    // The same file, a new viewer: +Z from the start, no other up axis shown first.
    let dir2 = out_dir("up-window-again");
    let mut again = Running::start_with(&args, &dir2, &probe);
    again.wait_for("] opened ", 1, Duration::from_secs(120));
    again.wait_for("ui probe: up axis = ", 1, Duration::from_secs(60));
    let shown: Vec<String> = again
        .log_text()
        .lines()
        .filter_map(|l| l.split("ui probe: up axis = ").nth(1).map(str::to_string))
        .collect();
    assert_eq!(shown, ["+Z"], "the up axes shown after opening again");
    let window = again.focus_window();
    std::thread::sleep(Duration::from_secs(2));
    let reopened = again.screenshot(&window, &dir2, 1);
    let from_z = differing_pixels(&z_up, &reopened, 12);
    let from_y = differing_pixels(&y_up, &reopened, 12);
    println!("reopened: {from_z} pixels differ from the +Z view, {from_y} from the +Y view");
    assert!(
        from_z * 4 < from_y,
        "reopened: {from_z} pixels from +Z, {from_y} from +Y"
    );
    again.validation_clean();
}
