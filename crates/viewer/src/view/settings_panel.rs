//! The panel's AO settings: one section per settings group (hrtao_core::settings), each drawing its group's
//! fields and nothing else. Adding a setting to a group means adding its widget here, in its group's function.
use hrtao_core::settings::{
    DisplaySettings, EditSettings, FilterSettings, MapSettings, StillSettings, YoungMapSettings,
};
use hrtao_core::Mode;

/// What is shown: the mode, shading and feature edges.
pub fn display(ui: &mut egui::Ui, s: &mut DisplaySettings) {
    egui::ComboBox::from_label("mode")
        .selected_text(s.mode.label())
        .show_ui(ui, |ui| {
            for m in Mode::ALL {
                ui.selectable_value(&mut s.mode, m, m.label());
            }
        })
        .response
        .on_hover_text(
            "HRTAO: the paper's hashed ray-traced AO (§1-§5). Per-pixel RTAO: the brute-force baseline \
             (accumulates while nothing moves). Debug views: hash cells (Fig. 3), LOD used (§4), samples \
             per cell.",
        );
    ui.horizontal(|ui| {
        ui.checkbox(&mut s.edges, "edges").on_hover_text(
            "Feature edges over the shading: silhouettes (depth and part changes) and creases. In \
             screenshots, never in the AO image.",
        );
        ui.add_enabled(
            s.edges,
            egui::Slider::new(&mut s.crease_deg, 5.0..=120.0).text("crease °"),
        )
        .on_hover_text("Faces meeting at more than this angle draw a crease line.");
    });
    ui.checkbox(&mut s.shaded, "base colours")
        .on_hover_text("Use the materials' base colours (off: uniform grey clay)");
}

/// The paper's hash map and sampling; `default_radius` is the scene's default AO radius.
pub fn map(ui: &mut egui::Ui, s: &mut MapSettings, default_radius: f32) {
    ui.add(
        egui::Slider::new(&mut s.s_p, 0.5..=32.0)
            .logarithmic(true)
            .text("s_p"),
    )
    .on_hover_text(
        "s_p (eq. 2): target size in pixels of a hash cell's footprint; the cell size s_w grows with \
         distance. Larger: coarser cells, fewer rays per cell needed, blurrier AO.",
    );
    ui.add(egui::Slider::new(&mut s.s_nd, 0.5..=16.0).text("s_nd"))
        .on_hover_text(
            "s_nd (eq. 5): normal discretisation; cells are keyed by position and quantised normal so \
             surfaces with different orientations don't share AO.",
        );
    let r0 = default_radius;
    ui.horizontal(|ui| {
        ui.add(
            egui::Slider::new(&mut s.ao_radius, r0 * 0.01..=r0 * 20.0)
                .logarithmic(true)
                .text("AO radius"),
        )
        .on_hover_text(
            "AO radius R (§1): occlusion rays longer than this count as unoccluded. Default: 8 mm for the \
             bundled gearbox, 5% of the bounding-box diagonal otherwise.",
        );
        if ui.small_button("↺").on_hover_text("scene default").clicked() {
            s.ao_radius = r0;
        }
    });
    ui.add(
        egui::Slider::new(&mut s.max_samples, 16..=10000)
            .logarithmic(true)
            .text("max samples"),
    )
    .on_hover_text(
        "Maximum samples per cell (§6, 1000 in the paper): a converged cell stops receiving rays, \
         freeing the budget for the others.",
    );
    ui.add(egui::Slider::new(&mut s.min_samples, 0..=256).text("min samples"))
        .on_hover_text(
            "Minimum samples (§4): a cell with fewer samples is replaced by its coarser LOD (eq. 3) \
             until it has gathered enough.",
        );
    ui.horizontal(|ui| {
        ui.checkbox(&mut s.cell_cap, "cell cap").on_hover_text(
            "Ours (docs/algorithm.md): the finest cell is at most a quarter of the AO radius, so cells stay \
             small against the contact shadows they store. Off: eq. 2-3 alone (and edits empty the whole map).",
        );
        ui.checkbox(&mut s.offset_bins, "offset normal bins").on_hover_text(
            "Ours: eq. 5's bins shifted by a quarter bin, so axis-aligned faces and 30°/45°/60° chamfers never \
             sit on a bin edge. Off: eq. 5 as published.",
        );
    });
    let mut log2 = s.hash_capacity.trailing_zeros();
    ui.add(
        egui::Slider::new(&mut log2, 10..=26)
            .text("hash capacity (log2)")
            .custom_formatter(|v, _| format!("2^{v} = {}", 1u64 << v as u32)),
    )
    .on_hover_text(
        "Hash map capacity in cells (§1, §6): the world-space cache of AO values. Changing it empties the \
         cache. Watch the load factor and failed inserts in the statistics.",
    );
    s.hash_capacity = 1 << log2;
}

/// The adaptive à-trous filter.
pub fn filter(ui: &mut egui::Ui, s: &mut FilterSettings) {
    ui.horizontal(|ui| {
        ui.add(egui::Slider::new(&mut s.filter_iterations, 0..=8).text("filter iterations"))
            .on_hover_text(
                "Adaptive à-trous filter (§5): each iteration doubles its reach; the footprint follows the cell \
                 size. 0: no filter.",
            );
        ui.checkbox(&mut s.variance_filter, "variance-guided").on_hover_text(
            "Ours: the filter also smooths young cells' noise over more than a cell and stops where neighbours \
             differ by more than the cells' noise. Off: the paper's filter (bounded by the cell footprint).",
        );
    });
}

/// The first frames of a young map.
pub fn young(ui: &mut egui::Ui, s: &mut YoungMapSettings) {
    ui.label("first frames (ours, docs/algorithm.md):");
    ui.horizontal_wrapped(|ui| {
        ui.checkbox(&mut s.adaptive_rays, "adaptive rays").on_hover_text(
            "While the hash map is young, pixels trace a quarter of the ray budget first and the rest goes to \
             the cells that are still noisy. Off: every pixel traces the same number of rays (the paper).",
        );
        ui.checkbox(&mut s.near_field, "contact correction").on_hover_text(
            "Each pixel corrects its cell's AO with its own rays that hit within half the AO radius, restoring \
             contact shadows a cell averages away, where its neighbours' rays agree. Off: the paper's cells.",
        );
        ui.checkbox(&mut s.level_blend, "level blend").on_hover_text(
            "While a pixel's finest cell is young, its AO leans on the next coarser level where the two agree \
             within the finest cell's noise. Off: the paper's finest level alone.",
        );
        ui.checkbox(&mut s.pooled_residual, "pooled residual").on_hover_text(
            "While a cell is young, each pixel is corrected by the rays it and its neighbours on the same \
             surface traced this frame, where they differ from the cell by more than their noise.",
        );
        ui.checkbox(&mut s.contact_detail, "contact detail").on_hover_text(
            "While cells are young, the creases and contacts the G-buffer shows around a pixel, finer than its \
             cells, darken it by a gain fitted each frame to the rays the pixels traced.",
        );
        ui.checkbox(&mut s.linear_cells, "linear cells").on_hover_text(
            "Each cell also keeps the slope of its AO across the cell and a pixel reads the cell's line at its \
             position. Only rays traced while it is on give a cell its slope (turning it on empties the map).",
        );
    });
}

/// Still-camera refinement.
pub fn still(ui: &mut egui::Ui, s: &mut StillSettings) {
    ui.horizontal(|ui| {
        ui.checkbox(&mut s.refine, "refine when still").on_hover_text(
            "Ours (docs/algorithm.md): while the view rests, each pixel traces its own rays and its AO converges \
             from the cell estimate to the ray-traced value, with anti-aliasing. Off: the paper's behaviour.",
        );
        ui.add_enabled(
            s.refine,
            egui::Slider::new(&mut s.still_samples, 8..=4096)
                .logarithmic(true)
                .text("rays per pixel"),
        )
        .on_hover_text("A still image is final once every pixel has this many rays of its own.");
    });
    ui.checkbox(&mut s.adaptive_prior, "adaptive cell weight").on_hover_text(
        "Ours: while a pixel's own rays agree with its cell, the cell counts as up to 1024 of the pixel's rays \
         (a steadier still image); where they show the cell is biased the weight falls to 32.",
    );
}

/// Scene edits.
pub fn edits(ui: &mut egui::Ui, s: &mut EditSettings) {
    ui.checkbox(&mut s.local_edits, "edits keep untouched AO")
        .on_hover_text(
        "Ours (docs/algorithm.md): moving, hiding or deleting a part re-keys only the hash cells within the \
         AO radius of it; the rest of the image keeps its converged AO. Off: the paper's eq. 6 (every edit \
         empties the map).",
    );
}
