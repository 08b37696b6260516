//! The storeys of a building (IFC's `IfcBuildingStorey`, `Scene::storeys`), listed in the panel's Scene section
//! with their elevations (the model tree holds them as nodes too): each can be isolated, or seen in plan (crate::plan: only its elements, cut at
//! its elevation plus the cut height, from the top in an orthographic view framing it). Entering a plan keeps the
//! view, the section planes and what was shown; leaving it (its button, Esc) restores them.
use glam::Vec3;
use hrtao_core::{Camera, Sections};
use hrtao_scene::Scene;

use super::command::{Command, ViewState};
use super::edits::Action;
use super::nav::{self, Nav};
use super::{tree, ui_probe};

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

impl Storeys {
    /// Into the plan view of `storey` (from the view before, or from another storey's plan), or out of it
    /// (None): the commands that show it (`nav`: the camera now, `sections`: the section planes now).
    pub fn plan(
        &mut self,
        storey: Option<usize>,
        scene: &Scene,
        nav: &Nav,
        sections: Sections,
    ) -> Vec<Command> {
        let mut out = Vec::new();
        // Leave the plan shown first: its view, sections and visibility come back (then the next plan is
        // entered from them).
        if let Some(k) = self.keep.take() {
            let restore = (k.visible.len() == scene.instances.len())
                .then(|| tree::set_visibility(scene, "leave the plan".into(), &k.visible))
                .flatten();
            out.push(Command::Camera {
                cam: k.cam,
                pivot: k.pivot,
            });
            out.push(Command::Sections(k.sections));
            out.extend(restore.map(|e| Command::Edit(Action::Apply(e))));
            log::info!("plan view left");
            out.extend(storey.map(|s| Command::Plan(Some(s))));
            return out;
        }
        let Some(storey) = storey else {
            return out;
        };
        let metres = crate::setup::metres_per_unit(scene, false);
        let plan = match crate::plan::plan(scene, storey, crate::plan::CUT_HEIGHT_M / metres) {
            Ok(p) => p,
            Err(e) => {
                out.push(Command::toast(format!("plan: {e}"), true));
                return out;
            }
        };
        let keep = Keep {
            storey,
            cam: nav.cam,
            pivot: nav.pivot,
            sections,
            visible: scene.instances.iter().map(|i| i.visible).collect(),
        };
        let name = scene.storeys[storey].name.clone();
        let shown = plan.visible.iter().filter(|v| **v).count();
        let edit = tree::set_visibility(scene, format!("plan of {name}"), &plan.visible);
        let cam = crate::plan::top_view(&nav.cam, &plan.bounds);
        out.push(Command::Walk(false));
        out.extend(edit.map(|e| Command::Edit(Action::Apply(e))));
        out.push(Command::Sections(plan.sections.clone()));
        out.push(Command::Camera {
            cam,
            pivot: nav::target(&cam),
        });
        self.keep = Some(keep);
        log::info!(
            "plan view of storey `{name}`: section at z = {} (file), {shown} instances shown",
            plan.cut as f64 + scene.origin[2]
        );
        out
    }
}
