//! The panel's load options: how OpenCASCADE turns a STEP or IGES file's B-rep faces into triangles, as the
//! command line's `--deflection`, `--deflection-mm` and `--angular-deflection` do. Kept in the preferences and
//! applied when a STEP/IGES file is opened or reopened (the scene on screen keeps its triangles until then).
//! Also the smoothing of meshes without normals of their own (STL, OBJ/PLY without normals), as the command line's
//! `--smooth-angle`/`--flat-normals` do, applied to files opened after it changes.
use hrtao_scene::CadTessellation;
use serde::{Deserialize, Serialize};

use super::command::{Command, ViewState};
use super::ui_probe;

/// Smallest and largest linear deflection relative to a part's size (fraction of its bounding-box diagonal).
const RELATIVE_RANGE: (f64, f64) = (1e-5, 0.1);
/// Smallest and largest linear deflection in millimetres.
const ABSOLUTE_RANGE_MM: (f64, f64) = (1e-4, 1e4);
/// Smallest and largest angular deflection in degrees (the worker's own limits).
const ANGULAR_RANGE_DEG: (f64, f64) = (0.5, 90.0);

/// The tessellation the user chose, as kept in the preferences (both linear values are kept, one is used).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct CadLoadOptions {
    /// The linear deflection is a fraction of each part's size (else one value in millimetres for every part).
    pub relative: bool,
    /// Linear deflection as a fraction of each part's bounding-box diagonal.
    pub relative_fraction: f64,
    /// Linear deflection in millimetres.
    pub absolute_mm: f64,
    /// Angular deflection in degrees: at most this angle between neighbouring triangles of a curved face.
    pub angular_deg: f64,
}

impl Default for CadLoadOptions {
    fn default() -> Self {
        CadLoadOptions::from_tessellation(CadTessellation::default())
    }
}

impl CadLoadOptions {
    /// The options showing `t` (the command line's flags, or the loader's defaults).
    pub fn from_tessellation(t: CadTessellation) -> CadLoadOptions {
        let d = CadTessellation::default();
        let relative = t.relative > 0.0;
        CadLoadOptions {
            relative,
            relative_fraction: if relative { t.relative } else { d.relative },
            absolute_mm: if relative { 0.1 } else { t.absolute },
            angular_deg: t.angular_deg,
        }
    }

    /// What the loader gets: the chosen linear deflection and the angle, each within its range (a value that is
    /// not a finite number, as a hand-edited preferences file may hold, gives the default).
    pub fn tessellation(&self) -> CadTessellation {
        let d = CadTessellation::default();
        let clamp = |v: f64, (lo, hi): (f64, f64), default: f64| {
            if v.is_finite() {
                v.clamp(lo, hi)
            } else {
                default
            }
        };
        let angular_deg = clamp(self.angular_deg, ANGULAR_RANGE_DEG, d.angular_deg);
        if self.relative {
            CadTessellation {
                relative: clamp(self.relative_fraction, RELATIVE_RANGE, d.relative),
                absolute: 0.0,
                angular_deg,
            }
        } else {
            CadTessellation {
                relative: 0.0,
                absolute: clamp(self.absolute_mm, ABSOLUTE_RANGE_MM, 0.1),
                angular_deg,
            }
        }
    }

    /// The load options of a file opened with these settings.
    pub fn load_options(&self) -> hrtao_scene::LoadOptions {
        let mut opts = hrtao_scene::LoadOptions::default();
        opts.cad.tessellation = self.tessellation();
        opts
    }
}

/// How meshes without normals of their own are shaded, as kept in the preferences (the angle is kept while
/// smoothing is off).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct MeshLoadOptions {
    /// Smooth normals by `crease_deg` (else face normals).
    pub smooth: bool,
    /// Faces meeting at up to this angle (degrees) share a normal; sharper edges stay creases.
    pub crease_deg: f32,
}

impl Default for MeshLoadOptions {
    fn default() -> Self {
        MeshLoadOptions::from_crease(Some(hrtao_scene::normals::DEFAULT_CREASE_DEG))
    }
}

impl MeshLoadOptions {
    /// The options showing a crease angle (`None`: face normals; the command line's flags).
    pub fn from_crease(crease_deg: Option<f32>) -> MeshLoadOptions {
        MeshLoadOptions {
            smooth: crease_deg.is_some(),
            crease_deg: crease_deg.unwrap_or(hrtao_scene::normals::DEFAULT_CREASE_DEG),
        }
    }

    /// What the loader gets: the angle within 0..=180 (a value that is not a number, as a hand-edited preferences
    /// file may hold, gives the default), or `None` when smoothing is off.
    pub fn crease_deg(&self) -> Option<f32> {
        let deg = if self.crease_deg.is_finite() {
            self.crease_deg.clamp(0.0, 180.0)
        } else {
            hrtao_scene::normals::DEFAULT_CREASE_DEG
        };
        self.smooth.then_some(deg)
    }
}

/// The load options of a file opened with the preferences' tessellation and smoothing.
pub fn load_options(prefs: &super::prefs::Prefs) -> hrtao_scene::LoadOptions {
    let mut opts = prefs.cad_load.load_options();
    opts.crease_deg = prefs.mesh_load.crease_deg();
    opts
}

/// Whether `spec` names a file the tessellation applies to (STEP or IGES, any case).
pub fn is_cad_file(spec: &str) -> bool {
    std::path::Path::new(spec)
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| ["step", "stp", "iges", "igs"].contains(&e.to_ascii_lowercase().as_str()))
}

/// The "Load options" section: the tessellation of STEP/IGES files (kept in the preferences), and reopening the
/// current file with it.
#[derive(Default)]
pub struct LoadOptionsPanel;

impl LoadOptionsPanel {
    pub fn ui(&mut self, ui: &mut egui::Ui, state: &ViewState) -> Vec<Command> {
        let ppp = ui.ctx().pixels_per_point();
        let mut prefs = state.prefs.clone();
        let o = &mut prefs.cad_load;
        ui.label("STEP / IGES tessellation (OpenCASCADE)");
        ui.horizontal(|ui| {
            let r = ui
                .radio_value(&mut o.relative, true, "relative to each part")
                .on_hover_text("Linear deflection as a fraction of each part's size (--deflection)");
            ui_probe::note("relative to each part", r.rect, ppp);
            let r = ui
                .radio_value(&mut o.relative, false, "in millimetres")
                .on_hover_text("One linear deflection for every part (--deflection-mm)");
            ui_probe::note("in millimetres", r.rect, ppp);
        });
        egui::Grid::new("cad_load_options").show(ui, |ui| {
            ui.label("linear deflection");
            if o.relative {
                let mut pct = o.relative_fraction * 100.0;
                let r = ui.add(
                    egui::DragValue::new(&mut pct)
                        .range(RELATIVE_RANGE.0 * 100.0..=RELATIVE_RANGE.1 * 100.0)
                        .speed(0.005)
                        .max_decimals(4)
                        .suffix(" % of the part"),
                );
                if r.changed() {
                    o.relative_fraction = pct / 100.0;
                }
            } else {
                let r = ui.add(
                    egui::DragValue::new(&mut o.absolute_mm)
                        .range(ABSOLUTE_RANGE_MM.0..=ABSOLUTE_RANGE_MM.1)
                        .speed(0.01)
                        .max_decimals(4)
                        .suffix(" mm"),
                );
                ui_probe::note("linear deflection mm", r.rect, ppp);
            }
            ui.end_row();
            ui.label("angular deflection");
            let r = ui.add(
                egui::DragValue::new(&mut o.angular_deg)
                    .range(ANGULAR_RANGE_DEG.0..=ANGULAR_RANGE_DEG.1)
                    .speed(0.1)
                    .max_decimals(2)
                    .suffix("°"),
            )
            .on_hover_text(
                "At most this angle between neighbouring triangles of a curved face (--angular-deflection); \
                 keep it at most the crease angle so that curved faces do not read as facets",
            );
            ui_probe::note("angular deflection", r.rect, ppp);
            ui.end_row();
        });
        if ui.button("Defaults").clicked() {
            *o = CadLoadOptions::default();
        }
        ui.separator();
        let m = &mut prefs.mesh_load;
        let r = ui
            .checkbox(&mut m.smooth, "Smooth meshes without normals")
            .on_hover_text(
                "STL, and OBJ/PLY files without normals: shade smoothly across edges whose faces meet at up to \
                 the angle (--smooth-angle); off: face normals (--flat-normals). Files with their own normals and \
                 glTF are shaded as they say. Applies to files opened from now on.",
            );
        ui_probe::note("Smooth meshes without normals", r.rect, ppp);
        let r = ui
            .add_enabled(
                m.smooth,
                egui::Slider::new(&mut m.crease_deg, 0.0..=180.0)
                    .step_by(1.0)
                    .suffix("°")
                    .text("smoothing angle"),
            )
            .on_hover_text(
                "Faces meeting at up to this angle share a normal; sharper edges stay creases. At the feature \
                 edges' crease angle (40° by default) smoothed surfaces get no crease lines.",
            );
        ui_probe::note("smoothing angle", r.rect, ppp);
        let mut out = Vec::new();
        if prefs != *state.prefs {
            out.push(Command::Prefs(Box::new(prefs)));
        }
        let reopen = (is_cad_file(state.spec) || is_mesh_file(state.spec)) && state.loading.is_none();
        let r = ui
            .add_enabled(reopen, egui::Button::new("Reopen with these options"))
            .on_hover_text(
                "Opens the current STEP/IGES, STL, OBJ or PLY file again; new files open with them too",
            );
        ui_probe::note("Reopen with these options", r.rect, ppp);
        if r.clicked() {
            out.push(Command::Open(state.spec.to_string()));
        }
        out
    }
}

/// Whether `spec` names a mesh file the smoothing may apply to (STL, OBJ, PLY, any case).
pub fn is_mesh_file(spec: &str) -> bool {
    std::path::Path::new(spec)
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| ["stl", "obj", "ply"].contains(&e.to_ascii_lowercase().as_str()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn options_become_the_loaders_tessellation() {
        let d = CadLoadOptions::default();
        assert_eq!(d.tessellation(), CadTessellation::default());
        assert_eq!(d.load_options().cad.tessellation, CadTessellation::default());
        // In millimetres: the relative deflection is off (the worker then uses the absolute one).
        let mm = CadLoadOptions {
            relative: false,
            absolute_mm: 1.0,
            angular_deg: 28.65,
            ..d
        };
        assert_eq!(
            mm.load_options().cad.tessellation,
            CadTessellation {
                relative: 0.0,
                absolute: 1.0,
                angular_deg: 28.65
            }
        );
        let rel = CadLoadOptions {
            relative: true,
            relative_fraction: 0.01,
            ..mm
        };
        assert_eq!(
            rel.tessellation(),
            CadTessellation {
                relative: 0.01,
                absolute: 0.0,
                angular_deg: 28.65
            }
        );
        // Out of range or not a number (a hand-edited file): clamped, or the default.
        let wild = CadLoadOptions {
            relative: true,
            relative_fraction: 5.0,
            absolute_mm: f64::NAN,
            angular_deg: f64::INFINITY,
        };
        let t = wild.tessellation();
        assert_eq!(
            (t.relative, t.angular_deg),
            (0.1, CadTessellation::default().angular_deg)
        );
        let t = CadLoadOptions {
            relative: false,
            ..wild
        }
        .tessellation();
        assert_eq!((t.relative, t.absolute), (0.0, 0.1));
        let t = CadLoadOptions {
            angular_deg: 0.0,
            ..d
        }
        .tessellation();
        assert_eq!(t.angular_deg, 0.5);
    }

    #[test]
    fn the_command_lines_flags_show_in_the_panel() {
        let mm = CadTessellation {
            relative: 0.0,
            absolute: 0.5,
            angular_deg: 20.0,
        };
        let o = CadLoadOptions::from_tessellation(mm);
        assert!(!o.relative);
        assert_eq!(o.tessellation(), mm);
        let rel = CadTessellation {
            relative: 0.002,
            absolute: 0.0,
            angular_deg: 5.0,
        };
        assert_eq!(CadLoadOptions::from_tessellation(rel).tessellation(), rel);
    }

    #[test]
    fn kept_in_the_preferences() {
        let mut p = super::super::prefs::Prefs::default();
        p.cad_load.relative = false;
        p.cad_load.absolute_mm = 0.25;
        let json = serde_json::to_string(&p).unwrap();
        let back: super::super::prefs::Prefs = serde_json::from_str(&json).unwrap();
        assert_eq!(back.cad_load, p.cad_load);
        // A preferences file from before the option: the defaults.
        let mut v: serde_json::Value = serde_json::from_str(&json).unwrap();
        v.as_object_mut().unwrap().remove("cad_load");
        let old: super::super::prefs::Prefs = serde_json::from_value(v).unwrap();
        assert_eq!(old.cad_load, CadLoadOptions::default());
    }

    /// The smoothing option: the loader's angle (default 40°, the renderer's feature-edge crease), None when off,
    /// clamped or the default from a hand-edited file, and the command line's flags shown in the panel.
    #[test]
    fn smoothing_becomes_the_loaders_crease_angle() {
        let d = MeshLoadOptions::default();
        assert_eq!(d.crease_deg(), Some(40.0));
        assert_eq!(
            d.crease_deg(),
            Some(hrtao_core::AoSettings::default().display.crease_deg),
            "the smoothing default is the feature edges' crease"
        );
        let mut p = super::super::prefs::Prefs::default();
        assert_eq!(load_options(&p).crease_deg, Some(40.0));
        p.mesh_load = MeshLoadOptions::from_crease(None);
        assert_eq!(load_options(&p).crease_deg, None);
        assert_eq!(p.mesh_load.crease_deg, 40.0, "the angle is kept while off");
        p.mesh_load = MeshLoadOptions::from_crease(Some(25.0));
        assert_eq!(load_options(&p).crease_deg, Some(25.0));
        for (wild, want) in [(f32::NAN, 40.0), (500.0, 180.0), (-3.0, 0.0)] {
            let o = MeshLoadOptions {
                smooth: true,
                crease_deg: wild,
            };
            assert_eq!(o.crease_deg(), Some(want), "{wild}");
        }
        // Kept in the preferences; a file from before the option gives the default.
        let json = serde_json::to_string(&p).unwrap();
        let back: super::super::prefs::Prefs = serde_json::from_str(&json).unwrap();
        assert_eq!(back.mesh_load, p.mesh_load);
        let mut v: serde_json::Value = serde_json::from_str(&json).unwrap();
        v.as_object_mut().unwrap().remove("mesh_load");
        let old: super::super::prefs::Prefs = serde_json::from_value(v).unwrap();
        assert_eq!(old.mesh_load, MeshLoadOptions::default());
    }

    #[test]
    fn step_and_iges_files_are_recognised() {
        for f in ["a.step", "b.STP", "dir/c.Iges", "d.igs"] {
            assert!(is_cad_file(f), "{f}");
        }
        for f in ["a.glb", "gen:box", "step", "x.step.gz"] {
            assert!(!is_cad_file(f), "{f}");
        }
        for f in ["a.stl", "b.OBJ", "c.Ply"] {
            assert!(is_mesh_file(f) && !is_cad_file(f), "{f}");
        }
        assert!(!is_mesh_file("a.gltf") && !is_mesh_file("a.step"));
    }
}
