//! How scene edits invalidate the map: the paper's F (eq. 6), or our local edits (`regions.rs`).
use super::settings_group;

settings_group! {
    /// Scene edits.
    pub struct EditSettings {
        /// Ours (docs/algorithm.md, `regions.rs`): an edit invalidates only the cells within reach of what it
        /// changed (region epochs in the key); off = eq. (6), every edit empties the whole map. Needs the cell
        /// cap (`MapSettings::cell_cap`), which bounds the cells the regions cover.
        local_edits: bool = true, Nothing, paper (false);
    }
}
