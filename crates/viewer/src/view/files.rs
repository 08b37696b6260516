//! The Open… dialog and dropped files. The dialog is a native file chooser (rfd: the XDG desktop portal over
//! D-Bus, zenity when no portal runs) on its own thread, so the view keeps rendering while it is open. Files
//! dropped on the window (winit's DroppedFile, through egui) go through `dropped_model`. Either loads like a
//! typed path: in the background, and a broken file keeps the current scene.
use std::path::PathBuf;
use std::sync::mpsc;
use std::time::{Duration, Instant};

use super::command::{Command, ViewState};

/// A dialog that returns nothing sooner than this never appeared (no portal, no zenity): say so.
const NO_DIALOG: Duration = Duration::from_millis(400);

/// What the dialog thread sends back: the chosen file (None: cancelled or no dialog) and how long it was open.
pub type DialogResult = (Option<PathBuf>, Duration);

/// The extensions the loaders read (STEP and IGES through OpenCASCADE).
pub const MODEL_EXTENSIONS: &[&str] = &hrtao_scene::SUPPORTED_EXTENSIONS;

/// The Open dialog's filter: its label names every extension it shows (`Models (.gltf, .glb, …)`).
pub fn filter_label() -> String {
    format!("Models ({})", crate::cli::formats())
}

/// The file to open from the paths dropped on the window: the first with a model extension (so dropping a
/// model with its .mtl or textures opens the model); None when nothing was dropped; an error naming the
/// paths when none is a model file.
pub fn dropped_model(paths: &[PathBuf]) -> Result<Option<PathBuf>, String> {
    if paths.is_empty() {
        return Ok(None);
    }
    let is_model = |p: &&PathBuf| {
        p.is_file()
            && p.extension()
                .map(|e| e.to_string_lossy().to_ascii_lowercase())
                .is_some_and(|e| MODEL_EXTENSIONS.contains(&e.as_str()))
    };
    match paths.iter().find(is_model) {
        Some(p) => Ok(Some(p.clone())),
        None => {
            let names: Vec<String> = paths.iter().map(|p| p.display().to_string()).collect();
            Err(format!(
                "cannot open {}: not a model file ({})",
                names.join(", "),
                MODEL_EXTENSIONS.join(", ")
            ))
        }
    }
}

/// The "Scene" section's open controls: a path or spec to type, Open, the Open… dialog, the bundled scene, the
/// running load and the last load error.
#[derive(Default)]
pub struct FilesPanel {
    /// The path in the text field.
    pub open_path: String,
    /// An Open… dialog running on its own thread: the chosen file arrives here.
    dialog: Option<mpsc::Receiver<DialogResult>>,
}

impl FilesPanel {
    pub fn new(spec: &str) -> FilesPanel {
        FilesPanel {
            open_path: spec.to_string(),
            dialog: None,
        }
    }

    pub fn ui(&mut self, ui: &mut egui::Ui, state: &ViewState) -> Vec<Command> {
        let mut out = Vec::new();
        let idle = state.loading.is_none();
        ui.horizontal(|ui| {
            let edit = ui.add(
                egui::TextEdit::singleline(&mut self.open_path)
                    .hint_text("model.step / .glb / .ifc / gen:city")
                    .desired_width(200.0),
            );
            let enter = edit.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
            if (ui.button("Open").clicked() || enter) && idle {
                out.push(Command::Open(self.open_path.trim().to_string()));
            }
            if ui
                .add_enabled(self.dialog.is_none(), egui::Button::new("Open…"))
                .on_hover_text("Choose a file (desktop portal, or zenity when no portal runs)")
                .clicked()
            {
                out.push(Command::OpenDialog);
            }
        })
        .response
        .on_hover_text(format!(
            "Open a model ({}) or a generator spec (drag & drop a file onto the window too)",
            crate::cli::formats()
        ));
        if ui.button("Open the bundled scene").clicked() && idle {
            out.push(Command::Open(super::default_spec()));
        }
        out.extend(recent_row(ui, state));
        if let Some(l) = &state.loading {
            let cancel = ui
                .horizontal(|ui| {
                    ui.spinner();
                    ui.label(format!("loading: {}", l.progress));
                    ui.button("Cancel")
                        .on_hover_text("Stop loading; the current scene stays")
                        .clicked()
                })
                .inner;
            if cancel {
                out.push(Command::CancelLoading);
            }
        }
        if let Some(e) = state.load_error {
            ui.colored_label(egui::Color32::from_rgb(230, 80, 70), e);
        }
        out
    }

    /// A scene opened: the text field shows it.
    pub fn opened(&mut self, spec: &str) {
        self.open_path = spec.to_string();
    }

    /// Files dropped on the window: opens the model among them (the current scene stays if it fails).
    pub fn dropped(paths: &[PathBuf]) -> Option<Command> {
        match dropped_model(paths) {
            Ok(Some(p)) => {
                log::info!("dropped file: {}", p.display());
                Some(Command::Open(p.display().to_string()))
            }
            Ok(None) => None,
            Err(e) => Some(Command::toast(e, true)),
        }
    }

    /// Opens the file chooser (one at a time), starting in the folder of `current` (the open scene's file).
    pub fn open_dialog(&mut self, current: &str, ctx: &egui::Context) -> Option<Command> {
        if self.dialog.is_some() {
            return None;
        }
        let start = std::path::Path::new(current)
            .parent()
            .filter(|d| d.is_dir())
            .map(PathBuf::from);
        let (tx, rx) = mpsc::channel();
        let ctx = ctx.clone();
        let spawned = std::thread::Builder::new()
            .name("open-dialog".into())
            .spawn(move || {
                let mut dialog = rfd::FileDialog::new()
                    .set_title("Open a model")
                    .add_filter(filter_label(), MODEL_EXTENSIONS)
                    .add_filter("All files", &["*"]);
                if let Some(dir) = start {
                    dialog = dialog.set_directory(dir);
                }
                let t0 = Instant::now();
                log::info!("file dialog opened");
                let _ = tx.send((dialog.pick_file(), t0.elapsed()));
                ctx.request_repaint();
            });
        match spawned {
            Ok(_) => {
                self.dialog = Some(rx);
                None
            }
            Err(e) => Some(Command::toast(format!("cannot open the file dialog: {e}"), true)),
        }
    }

    /// The file the dialog returned, if it has, to open (unless a load is running).
    pub fn poll_dialog(&mut self, loading: bool) -> Option<Command> {
        let rx = self.dialog.as_ref()?;
        match rx.try_recv() {
            Err(mpsc::TryRecvError::Empty) => None,
            Ok((Some(path), _)) => {
                self.dialog = None;
                log::info!("file dialog chose {}", path.display());
                (!loading).then(|| Command::Open(path.display().to_string()))
            }
            Ok((None, open_for)) => {
                self.dialog = None;
                (open_for < NO_DIALOG).then(|| {
                    Command::toast(
                        "no file dialog could be shown (it needs xdg-desktop-portal or zenity): type the path or drop the file on the window",
                        true,
                    )
                })
            }
            Err(mpsc::TryRecvError::Disconnected) => {
                self.dialog = None;
                None
            }
        }
    }
}

/// Names under which the recent entries' rectangles are probed (`ui_probe`), most recent first.
const RECENT_PROBES: [&str; super::recent::CAP] = [
    "recent 1",
    "recent 2",
    "recent 3",
    "recent 4",
    "recent 5",
    "recent 6",
    "recent 7",
    "recent 8",
    "recent 9",
    "recent 10",
];

/// The Recent menu (missing files disabled), Reload (F5) and the auto-reload switch.
fn recent_row(ui: &mut egui::Ui, state: &ViewState) -> Vec<Command> {
    let mut out = Vec::new();
    let ppp = ui.ctx().pixels_per_point();
    let idle = state.loading.is_none();
    ui.horizontal(|ui| {
        let menu = ui.add_enabled_ui(!state.prefs.recent.is_empty() && idle, |ui| {
            ui.menu_button("Recent", |ui| {
                // Looked up on disk only while the menu is open, not on every UI pass.
                let entries = super::recent::entries(&state.prefs.recent);
                for (k, (path, exists)) in entries.iter().enumerate() {
                    let label = path.display().to_string();
                    let b = ui
                        .add_enabled(*exists, egui::Button::new(&label))
                        .on_disabled_hover_text("the file is not there any more");
                    if let Some(name) = RECENT_PROBES.get(k) {
                        super::ui_probe::note(name, b.rect, ppp);
                    }
                    if b.clicked() {
                        out.push(Command::Open(label));
                        ui.close();
                    }
                }
            })
            .response
        });
        super::ui_probe::note("recent", menu.inner.rect, ppp);
        menu.response
            .on_hover_text("Recently opened files, most recent first");
        let file_open = std::path::Path::new(state.spec).is_file();
        if ui
            .add_enabled(file_open && idle, egui::Button::new("Reload"))
            .on_hover_text(
                "Open the file again, keeping the camera, section planes and selection (F5, Ctrl+R)",
            )
            .clicked()
        {
            out.push(Command::Reload);
        }
        let mut auto = state.prefs.auto_reload;
        if ui
            .checkbox(&mut auto, "Auto-reload")
            .on_hover_text("Reload the open file when it changes on disk")
            .changed()
        {
            let mut prefs = state.prefs.clone();
            prefs.auto_reload = auto;
            out.push(Command::Prefs(Box::new(prefs)));
        }
    });
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The dialog shows every extension the loaders read, and its label names each of them.
    #[test]
    fn the_dialog_filter_names_every_format() {
        assert_eq!(MODEL_EXTENSIONS, hrtao_scene::SUPPORTED_EXTENSIONS);
        let label = filter_label();
        for ext in hrtao_scene::SUPPORTED_EXTENSIONS {
            assert!(
                label.split([' ', '(', ')', ',']).any(|w| w == format!(".{ext}")),
                ".{ext} is missing from the label `{label}`"
            );
        }
    }

    /// A real file on disk, as a drop delivers it: the model is picked among the dropped paths and loads.
    #[test]
    fn a_dropped_model_file_is_picked_and_loads() {
        let dir = std::env::temp_dir().join(format!("hrtao-drop-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let obj = dir.join("Part.OBJ");
        std::fs::write(&obj, "o part\nv 0 0 0\nv 2 0 0\nv 0 3 0\nf 1 2 3\n").unwrap();
        let mtl = dir.join("part.mtl");
        std::fs::write(&mtl, "newmtl m\nKd 1 0 0\n").unwrap();
        let picked = dropped_model(&[mtl.clone(), obj.clone()]).unwrap();
        assert_eq!(picked.as_ref(), Some(&obj), "the model, not its .mtl");
        let scene = hrtao_scene::load(picked.unwrap().to_str().unwrap(), &mut |_| {}).unwrap();
        assert_eq!(scene.instances.len(), 1);
        let b = scene.bounds();
        assert_eq!((b.max - b.min).to_array(), [2.0, 3.0, 0.0]);
        // Nothing dropped; only a non-model file; a directory named like a model: clear errors, no load.
        assert_eq!(dropped_model(&[]), Ok(None));
        let err = dropped_model(std::slice::from_ref(&mtl)).unwrap_err();
        assert!(
            err.contains("part.mtl") && err.contains("not a model file"),
            "{err}"
        );
        let step = dir.join("Part.STP");
        std::fs::write(&step, "ISO-10303-21;").unwrap();
        assert_eq!(dropped_model(&[mtl.clone(), step.clone()]), Ok(Some(step)));
        let err = dropped_model(std::slice::from_ref(&mtl)).unwrap_err();
        assert!(err.contains("step") && err.contains("igs"), "{err}");
        let folder = dir.join("folder.stl");
        std::fs::create_dir_all(&folder).unwrap();
        assert!(dropped_model(&[folder]).is_err());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
