//! How scene edits invalidate the map: the paper's F (eq. 6), or our local edits (`regions.rs`).
use super::settings_group;

settings_group! {
    /// Scene edits.
    pub struct EditSettings {
        /// Ours: moving, hiding or deleting a part re-keys only the hash cells within the AO radius of it
        /// (region epochs in the key, `regions.rs`); the rest of the image keeps its converged AO. Off: the
        /// paper's eq. 6 (every edit empties the map). Needs the cell cap, which bounds the cells the regions
        /// cover.
        local_edits: bool = true, Nothing, paper (false);
    }
}
