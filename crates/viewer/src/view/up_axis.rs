//! The scene's up axis in the viewer: the panel's ±X/±Y/±Z choice (as F3D's up option), what it turns (the
//! fitted view and home, orbit, standard views, the view cube, walking and the sky light's zenith), and the
//! choice remembered per file beside the recent files (`Prefs::up_axes`), reused when that file opens again.
use std::path::{Path, PathBuf};

use hrtao_core::camera::UpAxis;
use hrtao_core::Camera;
use serde::{Deserialize, Serialize};

use super::command::{Command, ViewState};
use super::prefs::Prefs;
use super::{nav, recent, ui_probe};

/// The most files whose up axis is remembered.
pub const CAP: usize = 64;

/// A file's chosen up axis (canonical path).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FileUp {
    pub file: PathBuf,
    pub up: UpAxis,
}

/// The up axis the user chose for the file `spec` names, if any.
pub fn remembered(list: &[FileUp], spec: &str) -> Option<UpAxis> {
    let path = recent::entry_for(spec)?;
    list.iter().find(|f| same_file(&f.file, &path)).map(|f| f.up)
}

/// Remembers `up` for `path` (a canonical path): the newest choice first, one per file, at most `CAP`.
pub fn remember(list: &mut Vec<FileUp>, path: PathBuf, up: UpAxis) {
    list.retain(|f| !same_file(&f.file, &path));
    list.insert(0, FileUp { file: path, up });
    list.truncate(CAP);
}

fn same_file(a: &Path, b: &Path) -> bool {
    a == b || std::fs::canonicalize(a).ok() == std::fs::canonicalize(b).ok() && a.exists()
}

/// The panel's row: the up axis of the open scene, any of the six.
pub fn row(ui: &mut egui::Ui, state: &ViewState) -> Option<Command> {
    let current = state.nav.world_up;
    let mut chosen = current;
    ui.horizontal(|ui| {
        ui.label("Up");
        let combo = egui::ComboBox::from_id_salt("up axis")
            .selected_text(current.label())
            .width(56.0)
            .show_ui(ui, |ui| {
                for up in UpAxis::ALL {
                    let r = ui.selectable_value(&mut chosen, up, up.label());
                    ui_probe::note(item_probe(up), r.rect, ui.ctx().pixels_per_point());
                }
            });
        let rect = combo.response.rect;
        combo.response.on_hover_text(
            "The world direction that points up: the fitted view, orbit, the standard views, the view cube, \
             walking and the sky light's zenith follow it. IFC and 3MF are Z up by their specifications, glTF \
             is Y up; other formats open Y up. The choice is remembered for this file.",
        );
        ui_probe::note("up axis", rect, ui.ctx().pixels_per_point());
    });
    ui_probe::note_text("up axis", current.label());
    (chosen != current).then_some(Command::UpAxis(chosen))
}

/// The probe name of the popup's entry for `up`.
fn item_probe(up: UpAxis) -> &'static str {
    match up {
        UpAxis::X => "up axis +X",
        UpAxis::Y => "up axis +Y",
        UpAxis::Z => "up axis +Z",
        UpAxis::NegX => "up axis -X",
        UpAxis::NegY => "up axis -Y",
        UpAxis::NegZ => "up axis -Z",
    }
}

/// The camera fitted to `bounds` from the front-right-above direction of `up`, keeping `cam`'s lens and size.
pub fn refit(cam: &Camera, up: UpAxis, min: glam::Vec3, max: glam::Vec3) -> Camera {
    Camera {
        projection: cam.projection,
        ..Camera::fit(min, max, up, cam.fov_y_deg, cam.width, cam.height)
    }
}

/// The panel's choice: the scene turns upright about `up` (a fitted view from the new side, which is also
/// home), the sky's zenith follows (the map re-keys: its transfer vectors live in the sky frame), and the choice
/// is remembered for the open file `spec` (then the preferences are saved: true).
pub fn choose(
    up: UpAxis,
    scene: &hrtao_scene::Scene,
    spec: &str,
    (nav, home): (&mut nav::Nav, &mut Camera),
    prefs: &mut Prefs,
) -> bool {
    if up == nav.world_up {
        return false;
    }
    let b = scene.bounds();
    let cam = refit(&nav.cam, up, b.min, b.max);
    *nav = nav::Nav {
        cam,
        pivot: nav::target(&cam),
        world_up: up,
    };
    *home = cam;
    prefs.settings.light.sky_up = up;
    log::info!("up axis: {up} for {spec}");
    match recent::entry_for(spec) {
        Some(path) => {
            remember(&mut prefs.up_axes, path, up);
            true
        }
        None => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_files_choice_is_found_by_any_spelling_and_the_newest_wins() {
        let dir = std::env::temp_dir().join(format!("hrtao-up-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("sub")).unwrap();
        let a = dir.join("a.obj");
        std::fs::write(&a, "v 0 0 0\n").unwrap();
        let canonical = std::fs::canonicalize(&a).unwrap();
        let mut list = Vec::new();
        assert_eq!(remembered(&list, a.to_str().unwrap()), None);
        remember(&mut list, canonical.clone(), UpAxis::NegX);
        remember(&mut list, canonical.clone(), UpAxis::Z);
        assert_eq!(list.len(), 1);
        let other = dir.join("sub/../a.obj");
        assert_eq!(remembered(&list, other.to_str().unwrap()), Some(UpAxis::Z));
        assert_eq!(remembered(&list, "gen:city"), None);
        for k in 0..CAP + 5 {
            remember(&mut list, dir.join(format!("missing{k}.obj")), UpAxis::Y);
        }
        assert_eq!(list.len(), CAP);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_refit_looks_at_the_model_with_the_new_up_on_top() {
        let cam = Camera {
            width: 64,
            height: 48,
            ..Camera::fit(glam::Vec3::ZERO, glam::Vec3::ONE, UpAxis::Y, 40.0, 64, 48)
        };
        for up in UpAxis::ALL {
            let c = refit(&cam, up, glam::Vec3::ZERO, glam::Vec3::ONE);
            assert!(c.validate().is_ok());
            assert_eq!(nav::target(&c), glam::Vec3::splat(0.5));
            // Seen from above: the eye is higher than the target along the up axis, and the image's up leans
            // to it.
            assert!((nav::eye(&c) - nav::target(&c)).dot(up.vector()) > 0.0, "{up}");
            assert!(nav::cam_up(&c).dot(up.vector()) > 0.5, "{up}");
        }
    }
}
