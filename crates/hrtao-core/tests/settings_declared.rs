//! docs/command-line.md's settings table is the one `AoSettings::docs_table` makes from the settings'
//! declarations (`settings_group!`): every `--set` key with its default, valid values, class, panel label and
//! doc. After a change to a declaration, rewrite the table with
//! `HRTAO_BLESS_DOCS=1 cargo test -p hrtao-core --test settings_declared`.
use std::path::Path;

use hrtao_core::AoSettings;

const BEGIN: &str = "<!-- settings table: generated from the declarations (AoSettings::docs_table) -->\n";
const END: &str = "<!-- end of the settings table -->";

#[test]
fn the_command_line_docs_list_every_setting_as_declared() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/command-line.md");
    let page = std::fs::read_to_string(&path).unwrap();
    let start = page.find(BEGIN).expect("the table's start marker") + BEGIN.len();
    let end = start + page[start..].find(END).expect("the table's end marker");
    let table = AoSettings::docs_table();
    if page[start..end] != table {
        if std::env::var_os("HRTAO_BLESS_DOCS").is_some() {
            std::fs::write(&path, format!("{}{table}{}", &page[..start], &page[end..])).unwrap();
            return;
        }
        panic!(
            "docs/command-line.md's settings table is not the declarations' (rewrite it: HRTAO_BLESS_DOCS=1 \
             cargo test -p hrtao-core --test settings_declared):\n{table}"
        );
    }
    for f in AoSettings::fields() {
        assert!(
            page.contains(&format!("| `{}` |", f.name)),
            "{} is not listed",
            f.name
        );
    }
}
