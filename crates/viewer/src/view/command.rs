//! What the panels, the 3D view's input, the keyboard and scripted runs ask of the viewer: one `Command` enum,
//! applied in one place (`Viewer::apply`, view/mod.rs), and the read-only `ViewState` every panel draws from.
//! A panel owns its own state and never reaches into the viewer: `fn ui(&mut self, ui, &ViewState) ->
//! Vec<Command>` (egui's demo `backend_panel.rs`, rerun's `SystemCommand`).
use glam::Vec3;
use hrtao_core::{AoSettings, Camera, DeviceInfo, FrameReport, Sections};
use hrtao_scene::Scene;

use super::edits::Action;
use super::nav::Nav;
use super::prefs::Prefs;
use super::tree::Selection;

/// What a click or double-click in the 3D view picks the surface for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PickFor {
    /// Select the instance under the cursor alone (background: deselect).
    Select,
    /// Shift/Ctrl+click: add it to the selection or remove it.
    Toggle,
    /// Double-click: the orbit pivot goes to the surface point.
    Pivot,
    /// Measure mode: a measured point.
    Measure,
}

pub enum Command {
    /// Open a file or generator spec in the background (the current scene stays until it loads).
    Open(String),
    /// The Open… dialog (Ctrl+O).
    OpenDialog,
    /// Reload the open file, keeping the camera, sections and selection (F5, Ctrl+R; `reload.rs`).
    Reload,
    /// Stop the running load.
    CancelLoading,
    /// Make this the selection (a tree node, a toggled set, nothing).
    Select(Selection),
    /// Select one instance alone, as a pick does, and reveal its tree node (u32::MAX: nothing).
    SelectInstance(u32),
    /// Pick the surface at a point of the 3D view (fractions of its width and height).
    Pick { at: [f32; 2], purpose: PickFor },
    /// An edit, undo or redo (F increments, TLAS rebuilt).
    Edit(Action),
    /// Delete the whole selection as one edit.
    DeleteSelection,
    /// New AO settings (checked first; an invalid set is refused with a toast).
    Settings(Box<AoSettings>),
    /// New preferences (budget, target, screenshot options, bookmarks, load options).
    Prefs(Box<Prefs>),
    /// The user's render scale (the internal resolution of a still image).
    RenderScale(f32),
    /// Forget all cached AO.
    ClearCache,
    /// Walk mode on (standing below the eye) or off (G, Esc, the panel's switch).
    Walk(bool),
    /// The plan view of a storey (`storeys.rs`), or back from it (None).
    Plan(Option<usize>),
    /// The scene's up axis, chosen in the panel (remembered for the file).
    UpAxis(hrtao_core::camera::UpAxis),
    /// The camera and orbit pivot move (navigation, standard views, bookmarks).
    Camera { cam: Camera, pivot: Vec3 },
    /// The pointer's drag over the view: held (the view counts as moving), and whether it moved this frame.
    Drag { dragging: bool, moved: bool },
    /// The section planes (scene coordinates) of the panel or of a Ctrl+Shift+drag.
    Sections(Sections),
    /// A screenshot (F12, the button): the window's size now, or a custom size in the background.
    Screenshot,
    /// Drop the background screenshot.
    CancelScreenshot(&'static str),
    /// Full screen on or off (F11).
    Fullscreen(bool),
    /// Close the window (Ctrl+Q).
    Quit,
    /// Where the 3D view lies in the window (x, y, width, height in pixels), as this frame laid it out.
    ViewRect([i32; 4]),
    /// A message for the user.
    Toast { text: String, error: bool },
    // Scripted runs (`script.rs`).
    /// The window's inner size in pixels (`--resize-at-frame`).
    WindowSize(u32, u32),
    /// Settings overrides (JSON, as `--set` takes them) on the settings in force; an error is fatal (`what`
    /// names the option).
    SetJson { json: String, what: String },
    /// Capture the window (3D view and UI) with the next presented frame (`--screenshot-ui`).
    CaptureWindow(std::path::PathBuf),
    /// A screenshot of `size` rendered in the background (`--screenshot-size`).
    BackgroundShot {
        size: (u32, u32),
        path: std::path::PathBuf,
    },
    /// The scripted run's frames are done: its screenshot, its statistics, the exit (once the background
    /// screenshot is written, with `after_shot`).
    FinishScript { after_shot: bool },
}

impl Command {
    pub fn toast(text: impl Into<String>, error: bool) -> Command {
        Command::Toast {
            text: text.into(),
            error,
        }
    }
}

/// A running load as the panels show it.
pub struct LoadingView<'a> {
    pub spec: &'a str,
    pub progress: &'a str,
    pub seconds: f32,
}

/// Everything a panel may read about the viewer this frame.
pub struct ViewState<'a> {
    pub device: &'a DeviceInfo,
    pub validation_messages: u32,
    pub scene: Option<&'a Scene>,
    /// The open scene's file or spec.
    pub spec: &'a str,
    pub section_sides: Option<[usize; 3]>,
    pub selection: &'a Selection,
    pub nav: &'a Nav,
    /// Walk mode is on (`walk.rs`): the keys walk and the left drag looks around.
    pub walking: bool,
    /// The storey shown in plan (`storeys.rs`; Esc leaves it).
    pub in_plan: Option<usize>,
    /// The camera the scene opened with (Enter).
    pub home: Camera,
    pub prefs: &'a Prefs,
    /// The open scene's default AO radius.
    pub default_radius: f32,
    pub render_scale: f32,
    /// The swapchain blits the internal image (a render scale below 1 is possible).
    pub can_scale: bool,
    /// The 3D view in window pixels: x, y, width, height.
    pub view_rect: [i32; 4],
    pub report: Option<&'a FrameReport>,
    /// The renderer's internal resolution.
    pub internal: (u32, u32),
    /// Average render and interval milliseconds of the view's frames.
    pub frame_ms: (f64, f64),
    /// The rays per frame in use (the frame-time target's, or the user's).
    pub rays_per_frame: u32,
    /// The frame-time target in force (the user's, or the device's), milliseconds.
    pub target_ms: f64,
    pub loading: Option<LoadingView<'a>>,
    pub load_error: Option<&'a str>,
    pub undo: Option<String>,
    pub redo: Option<String>,
    /// A background screenshot's progress (fraction, text), and whether it can still be cancelled.
    pub shot: Option<(f32, String, bool)>,
}

impl ViewState<'_> {
    /// The camera at the 3D view's size (for rays through view points and for fitting).
    pub fn view_cam(&self) -> Camera {
        Camera {
            width: self.view_rect[2].max(1) as u32,
            height: self.view_rect[3].max(1) as u32,
            ..self.nav.cam
        }
    }

    /// One percent of the scene's diagonal: a move step and the fly speed's unit.
    pub fn move_step(&self) -> f32 {
        self.scene
            .map(|s| s.bounds().diagonal().length() * 0.01)
            .unwrap_or(1.0)
            .max(1e-6)
    }
}
