//! The pass list: every compute pass of a frame, in frame order, the paper's (`pass.rs`) and our additions'
//! (`crate::additions`). The renderer builds the pipelines of these (`PassSet::new`), and the pass table of
//! docs/architecture.md lists them. Above both `pass.rs` and the additions, so neither imports the other's list.
use crate::additions;
use crate::pass::{Pass, Resource};
use crate::probes;

/// Every compute pass, in frame order (the pass table's rows).
pub const ALL: [Pass; 12] = [
    Pass::PRIMARY,
    Pass::GBUFFER_FROM_VIS,
    probes::PROBE,
    additions::contact_detail::OBSCURANCE,
    Pass::RTAO,
    Pass::CELL_FINDER,
    Pass::AO_UPDATE,
    Pass::RESOLVE,
    Pass::FILTER,
    additions::CORRECTIONS,
    Pass::COMPOSITE,
    Pass::HASH_TEST,
];

/// The pass table of docs/architecture.md, rendered from the declarations: one row per pass in frame order,
/// with its shader, its Table-2 timing section and the buffers it reads and writes.
pub fn pass_table_markdown() -> String {
    let list = |rs: &[Resource]| {
        if rs.is_empty() {
            "—".to_string()
        } else {
            rs.iter().map(|r| format!("{r:?}")).collect::<Vec<_>>().join(", ")
        }
    };
    let mut out = String::from("| pass | section | reads | writes |\n|---|---|---|---|\n");
    for pass in ALL {
        out += &format!(
            "| `shaders/{}.comp` | {} | {} | {} |\n",
            pass.shader(),
            pass.section(),
            list(pass.reads()),
            list(pass.writes())
        );
    }
    out
}
