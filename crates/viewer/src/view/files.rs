//! The Open… dialog: a native file chooser (rfd: the XDG desktop portal over D-Bus, zenity when no portal
//! runs) on its own thread, so the view keeps rendering while it is open. The chosen file loads like a typed
//! path or a dropped file: in the background, and a broken file keeps the current scene.
use std::path::PathBuf;
use std::sync::mpsc;
use std::time::{Duration, Instant};

use super::Viewer;

/// A dialog that returns nothing sooner than this never appeared (no portal, no zenity): say so.
const NO_DIALOG: Duration = Duration::from_millis(400);

/// What the dialog thread sends back: the chosen file (None: cancelled or no dialog) and how long it was open.
pub type DialogResult = (Option<PathBuf>, Duration);

/// The extensions the loaders read.
pub const MODEL_EXTENSIONS: &[&str] = &["glb", "gltf", "obj", "stl", "ply"];

impl Viewer {
    /// Opens the file chooser (one at a time).
    pub(crate) fn open_file_dialog(&mut self) {
        if self.open_dialog.is_some() {
            return;
        }
        let start = std::path::Path::new(&self.scene_spec)
            .parent()
            .filter(|d| d.is_dir())
            .map(PathBuf::from);
        let (tx, rx) = mpsc::channel();
        let ctx = self.egui_ctx.clone();
        let spawned = std::thread::Builder::new()
            .name("open-dialog".into())
            .spawn(move || {
                let mut dialog = rfd::FileDialog::new()
                    .set_title("Open a model")
                    .add_filter("Models (glTF, OBJ, STL, PLY)", MODEL_EXTENSIONS)
                    .add_filter("All files", &["*"]);
                if let Some(dir) = start {
                    dialog = dialog.set_directory(dir);
                }
                let t0 = Instant::now();
                let _ = tx.send((dialog.pick_file(), t0.elapsed()));
                ctx.request_repaint();
            });
        match spawned {
            Ok(_) => self.open_dialog = Some(rx),
            Err(e) => self.toast(format!("cannot open the file dialog: {e}"), true),
        }
    }

    /// Starts loading the file the dialog returned, if it has.
    pub(crate) fn poll_open_dialog(&mut self) {
        let Some(rx) = &self.open_dialog else {
            return;
        };
        match rx.try_recv() {
            Err(mpsc::TryRecvError::Empty) => {}
            Ok((Some(path), _)) => {
                self.open_dialog = None;
                if self.loading.is_none() {
                    self.start_loading(path.display().to_string());
                }
            }
            Ok((None, open_for)) => {
                self.open_dialog = None;
                if open_for < NO_DIALOG {
                    self.toast(
                        "no file dialog could be shown (it needs xdg-desktop-portal or zenity): type the path or drop the file on the window",
                        true,
                    );
                }
            }
            Err(mpsc::TryRecvError::Disconnected) => self.open_dialog = None,
        }
    }
}
