//! How a click changes the selection, in the 3D view and in the model tree alike: Shift or Ctrl (Cmd) toggles
//! the clicked instance in the selection, a plain click selects it alone.
use egui::PointerButton;

/// Whether this frame's click toggles the selection: Shift or Ctrl held when the last primary button event of
/// the frame happened (a quick Shift+click can press and release Shift within one frame's events, so the
/// frame's final modifiers may no longer hold it).
pub(crate) fn click_toggles(ctx: &egui::Context) -> bool {
    let m = ctx.input(|i| {
        i.events
            .iter()
            .rev()
            .find_map(|e| match e {
                egui::Event::PointerButton {
                    button: PointerButton::Primary,
                    modifiers,
                    ..
                } => Some(*modifiers),
                _ => None,
            })
            .unwrap_or(i.modifiers)
    });
    m.shift || m.command
}
