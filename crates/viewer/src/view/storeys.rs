//! The storeys of a building (IFC's `IfcBuildingStorey`, `Scene::storeys`), listed in the panel's Scene section
//! with their elevations (the model tree holds them as nodes too): each can be isolated, or seen in plan (crate::plan: only its elements, cut at
//! its elevation plus the cut height, from the top in an orthographic view framing it). Entering a plan keeps the
//! view, the section planes and what was shown; leaving it (its button, Esc) restores them.
use glam::Vec3;
use hrtao_core::{Camera, Sections};

use super::command::{Command, ViewState};
use super::edits::Action;
use super::{nav, tree, ui_probe};

/// What a plan view replaced, restored when it is left.
struct Keep {
    storey: usize,
    cam: Camera,
    pivot: Vec3,
    sections: Sections,
    visible: Vec<bool>,
}

/// The storeys' state (the panels own it: `ui::Panels::storeys`).
#[derive(Default)]
pub struct Storeys {
    keep: Option<Keep>,
}

impl Storeys {
    /// The storey shown in plan, if any.
    pub fn in_plan(&self) -> Option<usize> {
        self.keep.as_ref().map(|k| k.storey)
    }

    /// Another scene: no plan to leave.
    pub fn scene_opened(&mut self) {
        self.keep = None;
    }
}

/// The storeys' rows (nothing for a model without storeys).
pub fn panel(ui: &mut egui::Ui, state: &ViewState, in_plan: Option<usize>) -> Vec<Command> {
    let mut out = Vec::new();
    let Some(scene) = state.scene.filter(|s| !s.storeys.is_empty()) else {
        return out;
    };
    let unit = crate::setup::metres_per_unit(scene, false) as f64;
    ui.label(format!("Storeys ({})", scene.storeys.len()));
    // Highest first, as a building's section reads.
    let mut order: Vec<usize> = (0..scene.storeys.len()).collect();
    order.sort_by(|&a, &b| scene.storeys[b].elevation.total_cmp(&scene.storeys[a].elevation));
    let lowest = order.last().copied();
    egui::Grid::new("storeys").num_columns(3).show(ui, |ui| {
        for k in order {
            let s = &scene.storeys[k];
            let elevation_m = (s.elevation as f64 + scene.origin[2]) * unit;
            ui.label(format!("{}  {elevation_m:+.2} m", s.name));
            if ui
                .small_button("Isolate")
                .on_hover_text("Show only this storey's elements (U shows all)")
                .clicked()
            {
                let sel = tree::Selection::of_node(&scene.tree, s.node);
                out.extend(tree::isolate_edit(scene, &sel).map(|e| Command::Edit(Action::Apply(e))));
            }
            let label = if in_plan == Some(k) { "Leave plan" } else { "Plan" };
            let r = ui.small_button(label).on_hover_text(format!(
                "Floor plan: this storey alone, cut {} m above its elevation, seen from the top (Esc leaves)",
                crate::plan::CUT_HEIGHT_M
            ));
            if Some(k) == lowest {
                // Window tests click the lowest storey's plan.
                ui_probe::note("storey plan", r.rect, ui.ctx().pixels_per_point());
            }
            if r.clicked() {
                out.push(Command::Plan((in_plan != Some(k)).then_some(k)));
            }
            ui.end_row();
        }
    });
    out
}

impl super::Viewer {
    /// Into the plan view of `storey` (from the view before, or from another storey's plan), or out of it (None).
    pub(super) fn plan_view(&mut self, storey: Option<usize>) {
        let Some(scene) = &self.scene else {
            return;
        };
        // Leave the plan shown first: its view, sections and visibility come back.
        if let Some(k) = self.panels.storeys.keep.take() {
            let restore = (k.visible.len() == scene.instances.len())
                .then(|| tree::set_visibility(scene, "leave the plan".into(), &k.visible))
                .flatten();
            self.nav.cam = k.cam;
            self.nav.pivot = k.pivot;
            self.apply_sections(k.sections);
            if let Some(e) = restore {
                self.edit(Action::Apply(e));
            }
            log::info!("plan view left");
            if storey.is_none() {
                return;
            }
        }
        let Some(storey) = storey else { return };
        let Some(scene) = &self.scene else {
            return;
        };
        let metres = crate::setup::metres_per_unit(scene, false);
        let plan = match crate::plan::plan(scene, storey, crate::plan::CUT_HEIGHT_M / metres) {
            Ok(p) => p,
            Err(e) => {
                self.toast(format!("plan: {e}"), true);
                return;
            }
        };
        let keep = Keep {
            storey,
            cam: self.nav.cam,
            pivot: self.nav.pivot,
            sections: self
                .scene_gpu
                .as_ref()
                .map(|sg| sg.sections().clone())
                .unwrap_or_default(),
            visible: scene.instances.iter().map(|i| i.visible).collect(),
        };
        let name = scene.storeys[storey].name.clone();
        let shown = plan.visible.iter().filter(|v| **v).count();
        let edit = tree::set_visibility(scene, format!("plan of {name}"), &plan.visible);
        let cam = crate::plan::top_view(&self.nav.cam, &plan.bounds);
        self.set_walking(false, None);
        if let Some(e) = edit {
            self.edit(Action::Apply(e));
        }
        self.apply_sections(plan.sections.clone());
        self.nav.cam = cam;
        self.nav.pivot = nav::target(&cam);
        self.panels.storeys.keep = Some(keep);
        log::info!(
            "plan view of storey `{name}`: section at z = {} (file), {shown} instances shown",
            plan.cut as f64 + self.scene.as_ref().map_or(0.0, |s| s.origin[2])
        );
    }
}
