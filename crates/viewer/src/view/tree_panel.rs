//! The "Model tree" panel: a search box, Hide / Isolate / Show all, and the tree's rows. Only the rows the
//! scroll area shows are laid out (`ScrollArea::show_rows` over the open nodes flattened depth first), so an
//! assembly of a hundred thousand parts costs the UI what a screenful of rows costs, and every child of a node
//! is listed (no "… N more"). Clicks become commands; the tree's selection logic and edits live in `tree.rs`.
use std::collections::HashSet;

use hrtao_scene::{NodeTree, Scene};

use super::command::Command;
use super::edits::Action;
use super::tree::{hide_selection_edit, isolate_edit, set_node_visible, show_all, Selection};

/// The tree's scroll area: its height when the rows overflow it.
const TREE_HEIGHT: f32 = 320.0;

/// Frames during which a revealed node is scrolled to (the panel's own scroll area follows the tree's).
const REVEAL_FRAMES: u8 = 3;

/// One row as drawn: a node at its depth below a root.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Row {
    node: u32,
    depth: u32,
}

/// Panel state: the search text, which nodes are open, the node to reveal, and per-node counts cached per
/// scene version.
#[derive(Default)]
pub struct TreeView {
    pub search: String,
    /// Nodes whose open state differs from the default (roots open, every other node closed).
    toggled: HashSet<u32>,
    /// Open this node's ancestors and scroll to it (after a pick in the view), for a few frames.
    reveal: Option<(u32, u8)>,
    cache_key: Option<(u32, usize)>,
    counts: Vec<u64>,
    visible: Vec<u64>,
}

/// What a click in the tree asks for (applied after drawing, when the scene is no longer borrowed).
enum TreeAction {
    Select(u32),
    /// Shift/Ctrl+click: add the node's instances to the selection or remove them.
    Toggle(u32),
    Visible(u32, bool),
    /// The node's arrow: open or close it.
    Open(u32, bool),
}

impl TreeAction {
    /// A click on a node's row: Shift or Ctrl toggles it in the selection, a plain click selects it.
    fn click(ui: &egui::Ui, node: u32) -> Self {
        if super::selection::click_toggles(ui.ctx()) {
            TreeAction::Toggle(node)
        } else {
            TreeAction::Select(node)
        }
    }
}

impl TreeView {
    /// Opens the path to `node` and scrolls to it (None: nothing to reveal).
    pub fn reveal(&mut self, node: Option<u32>) {
        self.reveal = node.map(|n| (n, REVEAL_FRAMES));
    }

    /// The node to reveal this frame, counting the frames down.
    fn reveal_now(&mut self) -> Option<u32> {
        let (node, left) = self.reveal?;
        self.reveal = (left > 1).then_some((node, left - 1));
        Some(node)
    }

    fn refresh(&mut self, scene: &Scene) {
        let key = (scene.f(), scene.instances.len());
        if self.cache_key != Some(key) || self.counts.len() != scene.tree.len() {
            self.counts = scene.tree.instance_counts();
            self.visible = scene
                .tree
                .counts_where(|i| scene.instances.get(i as usize).is_some_and(|x| x.visible));
            self.cache_key = Some(key);
        }
    }

    fn is_open(&self, tree: &NodeTree, node: u32) -> bool {
        tree.nodes[node as usize].parent.is_none() != self.toggled.contains(&node)
    }

    fn set_open(&mut self, tree: &NodeTree, node: u32, open: bool) {
        if self.is_open(tree, node) != open && !self.toggled.remove(&node) {
            self.toggled.insert(node);
        }
    }

    /// The rows the open nodes show, depth first in the file's order.
    fn rows(&self, tree: &NodeTree) -> Vec<Row> {
        let mut rows = Vec::new();
        let roots: Vec<u32> = tree.roots().collect();
        let mut stack: Vec<Row> = roots.iter().rev().map(|&node| Row { node, depth: 0 }).collect();
        while let Some(row) = stack.pop() {
            rows.push(row);
            if self.is_open(tree, row.node) {
                let children = &tree.nodes[row.node as usize].children;
                stack.extend(children.iter().rev().map(|&node| Row {
                    node,
                    depth: row.depth + 1,
                }));
            }
        }
        rows
    }

    /// The "Model tree" section: search, hide/isolate/show all, and the rows; clicks become commands.
    pub fn ui(&mut self, ui: &mut egui::Ui, scene: Option<&Scene>, selection: &Selection) -> Vec<Command> {
        let Some(scene) = scene else {
            ui.label("no scene");
            return Vec::new();
        };
        self.refresh(scene);
        let mut out = Vec::new();
        ui.horizontal(|ui| {
            ui.label("Search");
            ui.add(egui::TextEdit::singleline(&mut self.search).desired_width(160.0));
        });
        ui.horizontal(|ui| {
            let has = !selection.instances.is_empty();
            let mut edit = None;
            if ui
                .add_enabled(has, egui::Button::new("Hide"))
                .on_hover_text("Hide the selection (H)")
                .clicked()
            {
                edit = hide_selection_edit(scene, selection);
            }
            if ui
                .add_enabled(has, egui::Button::new("Isolate"))
                .on_hover_text("Show only the selection (I)")
                .clicked()
            {
                edit = isolate_edit(scene, selection);
            }
            if ui
                .button("Show all")
                .on_hover_text("Show every instance (U)")
                .clicked()
            {
                edit = show_all(scene);
            }
            out.extend(edit.map(|e| Command::Edit(Action::Apply(e))));
        });
        let tree = &scene.tree;
        let query = self.search.trim().to_owned();
        let reveal = self.reveal_now().filter(|&n| (n as usize) < tree.len());
        let rows = if query.is_empty() {
            if let Some(node) = reveal {
                // Its ancestors open; the node itself keeps its state.
                for a in tree.path(node).into_iter().filter(|&a| a != node) {
                    self.set_open(tree, a, true);
                }
            }
            self.rows(tree)
        } else {
            let hits = tree.search(&query);
            if hits.is_empty() {
                ui.weak("no node matches");
            }
            hits.into_iter().map(|node| Row { node, depth: 0 }).collect()
        };
        let row_height = ui.spacing().interact_size.y;
        let pitch = row_height + ui.spacing().item_spacing.y;
        let mut area = egui::ScrollArea::vertical()
            .id_salt("model-tree")
            .max_height(TREE_HEIGHT)
            .auto_shrink([false, true]);
        let revealed_row = reveal.and_then(|n| rows.iter().position(|r| r.node == n));
        if let Some(i) = revealed_row {
            // The row in the middle of the tree's area (the area clamps the offset to its content).
            area = area.vertical_scroll_offset((i as f32 * pitch - (TREE_HEIGHT - pitch) / 2.0).max(0.0));
        }
        let mut actions = Vec::new();
        let shown = area.show_rows(ui, row_height, rows.len(), |ui, range| {
            // One line per row (long names end in "…"), so every row is `row_height` tall.
            ui.style_mut().wrap_mode = Some(egui::TextWrapMode::Truncate);
            for row in &rows[range] {
                self.row_ui(
                    ui,
                    tree,
                    *row,
                    row_height,
                    selection.node,
                    !query.is_empty(),
                    &mut actions,
                );
            }
        });
        if revealed_row.is_some() {
            // The tree's area scrolled to the row; the panel scrolls to the tree.
            ui.scroll_to_rect(shown.inner_rect, Some(egui::Align::Center));
        }
        for action in actions {
            out.push(match action {
                // A node's subtree is highlighted; a node of one instance is also what move and delete act on.
                TreeAction::Select(n) => Command::Select(Selection::of_node(tree, n)),
                TreeAction::Toggle(n) => Command::Select(selection.toggled_node(tree, n)),
                TreeAction::Visible(n, v) => match set_node_visible(scene, n, v) {
                    Some(e) => Command::Edit(Action::Apply(e)),
                    None => continue,
                },
                TreeAction::Open(n, open) => {
                    self.set_open(tree, n, open);
                    continue;
                }
            });
        }
        out
    }

    /// One row, exactly `height` tall: indentation, the open/close arrow (nodes with children, not in search
    /// results), hide/show, and the selectable name with its instance count.
    #[allow(clippy::too_many_arguments)]
    fn row_ui(
        &self,
        ui: &mut egui::Ui,
        tree: &NodeTree,
        row: Row,
        height: f32,
        selected: Option<u32>,
        flat: bool,
        actions: &mut Vec<TreeAction>,
    ) {
        let id = row.node;
        let node = &tree.nodes[id as usize];
        let (count, visible) = (self.counts[id as usize], self.visible[id as usize]);
        let (rect, _) =
            ui.allocate_exact_size(egui::vec2(ui.available_width(), height), egui::Sense::hover());
        let mut ui = ui.new_child(
            egui::UiBuilder::new()
                .id_salt(("tree-row", id))
                .max_rect(rect)
                .layout(egui::Layout::left_to_right(egui::Align::Center)),
        );
        let icon = ui.spacing().icon_width;
        ui.add_space(row.depth as f32 * ui.spacing().indent);
        if !flat && !node.children.is_empty() {
            let open = self.is_open(tree, id);
            let (_, arrow) = ui.allocate_exact_size(egui::vec2(icon, icon), egui::Sense::click());
            egui::collapsing_header::paint_default_icon(&mut ui, if open { 1.0 } else { 0.0 }, &arrow);
            if arrow.clicked() {
                actions.push(TreeAction::Open(id, !open));
            }
        } else if !flat {
            ui.add_space(icon + ui.spacing().item_spacing.x);
        }
        let all_visible = visible == count;
        if ui
            .small_button(if all_visible { "hide" } else { "show" })
            .clicked()
        {
            actions.push(TreeAction::Visible(id, !all_visible));
        }
        let hidden = if visible < count {
            format!(", {} hidden", count - visible)
        } else {
            String::new()
        };
        let label = ui
            .selectable_label(selected == Some(id), format!("{}  ({count}{hidden})", node.name))
            .on_hover_text(&node.name);
        if label.clicked() {
            actions.push(TreeAction::click(&ui, id));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// root(0) ─ a(1) ─ a1(3)
    ///          └ b(2)
    /// lone(4)
    fn tree() -> NodeTree {
        let mut t = NodeTree::default();
        let root = t.add("root", None);
        let a = t.add("a", Some(root));
        t.add("b", Some(root));
        t.add("a1", Some(a));
        t.add("lone", None);
        t
    }

    fn nodes(rows: &[Row]) -> Vec<(u32, u32)> {
        rows.iter().map(|r| (r.node, r.depth)).collect()
    }

    #[test]
    fn roots_open_and_other_nodes_closed_until_toggled() {
        let t = tree();
        let mut v = TreeView::default();
        assert_eq!(nodes(&v.rows(&t)), [(0, 0), (1, 1), (2, 1), (4, 0)]);
        v.set_open(&t, 1, true);
        assert_eq!(nodes(&v.rows(&t)), [(0, 0), (1, 1), (3, 2), (2, 1), (4, 0)]);
        v.set_open(&t, 0, false);
        assert_eq!(nodes(&v.rows(&t)), [(0, 0), (4, 0)]);
        // Reopening the root finds `a` as it was left; setting a state twice changes nothing.
        v.set_open(&t, 0, true);
        v.set_open(&t, 0, true);
        assert_eq!(nodes(&v.rows(&t)), [(0, 0), (1, 1), (3, 2), (2, 1), (4, 0)]);
        v.set_open(&t, 1, false);
        assert!(v.toggled.is_empty());
    }

    /// A root with `n` children named `part 0` … (one instance, owned by the root).
    fn wide_scene(n: usize) -> Scene {
        let mut s = hrtao_scene::load("gen:slab", &mut |_| {}).unwrap();
        let mut t = NodeTree::default();
        let root = t.add("assembly", None);
        t.nodes[root as usize].instances = (0..s.instances.len() as u32).collect();
        for i in 0..n {
            t.add(format!("part {i}"), Some(root));
        }
        s.tree = t;
        s.validate().unwrap();
        s
    }

    /// One frame of the panel in a bare egui context (400x600 points) fed `events`: its commands and the text
    /// it painted, with each text's rectangle.
    fn frame(
        ctx: &egui::Context,
        view: &mut TreeView,
        scene: &Scene,
        events: Vec<egui::Event>,
    ) -> (Vec<Command>, Vec<(String, egui::Rect)>) {
        let input = egui::RawInput {
            screen_rect: Some(egui::Rect::from_min_size(
                egui::Pos2::ZERO,
                egui::vec2(400.0, 600.0),
            )),
            events,
            ..Default::default()
        };
        let mut out = Vec::new();
        let output = ctx.run_ui(input, |root| {
            egui::CentralPanel::default().show(root, |ui| {
                out = view.ui(ui, Some(scene), &Selection::default());
            });
        });
        let texts = output
            .shapes
            .iter()
            .filter_map(|c| match &c.shape {
                egui::Shape::Text(t) => Some((t.galley.text().to_owned(), t.visual_bounding_rect())),
                _ => None,
            })
            .collect();
        output.drop_without_applying_deltas();
        (out, texts)
    }

    fn row_of<'a>(texts: &'a [(String, egui::Rect)], name: &str) -> Option<&'a egui::Rect> {
        let prefix = format!("{name}  (");
        texts.iter().find(|(t, _)| t.starts_with(&prefix)).map(|(_, r)| r)
    }

    /// Of an assembly of 20,000 parts the panel lays out only the rows its area shows, the rows it shows are
    /// the tree's first ones, a revealed part deep in the list is scrolled into view, and a click on its row
    /// selects it.
    #[test]
    fn a_wide_tree_draws_a_screenful_and_reveals_and_selects_any_row() {
        let scene = wide_scene(20_000);
        let ctx = egui::Context::default();
        let mut view = TreeView::default();
        let (_, texts) = frame(&ctx, &mut view, &scene, Vec::new());
        assert!(row_of(&texts, "assembly").is_some() && row_of(&texts, "part 0").is_some());
        let rows = texts.iter().filter(|(t, _)| t.starts_with("part ")).count();
        // 320 points of rows at 18 + 4 points each: 15 visible, plus the one show_rows adds below.
        assert!((10..=20).contains(&rows), "{rows} rows painted");
        assert!(row_of(&texts, "part 17000").is_none());

        view.reveal(Some(17_001));
        let mut texts = Vec::new();
        for _ in 0..REVEAL_FRAMES {
            texts = frame(&ctx, &mut view, &scene, Vec::new()).1;
        }
        let rect = *row_of(&texts, "part 17000").expect("the revealed row is painted");
        assert!(row_of(&texts, "part 0").is_none());
        let at = rect.center();
        let press = |pressed| egui::Event::PointerButton {
            pos: at,
            button: egui::PointerButton::Primary,
            pressed,
            modifiers: Default::default(),
        };
        frame(&ctx, &mut view, &scene, vec![egui::Event::PointerMoved(at)]);
        let (out, _) = frame(&ctx, &mut view, &scene, vec![press(true), press(false)]);
        let selected: Vec<Option<u32>> = out
            .iter()
            .filter_map(|c| match c {
                Command::Select(s) => Some(s.node),
                _ => None,
            })
            .collect();
        assert_eq!(selected, [Some(17_001)]);
    }
}
