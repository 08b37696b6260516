//! OBJ objects (`o`) and groups (`g`) as a model tree. tobj treats both alike and also splits a model at
//! every material change under the same name, so its models cannot be mapped back to the headers by name.
//! Before parsing, every header line is therefore replaced by a unique tag (`o \u{1}K`); each tobj model
//! then names the header K it came from. Objects become root nodes, groups children of the object before
//! them (roots if there is none); repeated names under the same parent share a node.

use std::collections::HashMap;

use crate::tree::NodeTree;

const TAG: char = '\u{1}';

/// The OBJ text with its header lines tagged, and the tree node of each header.
pub struct TaggedObj {
    pub text: Vec<u8>,
    pub tree: NodeTree,
    header_node: Vec<u32>,
}

impl TaggedObj {
    /// Tags the headers of `text` and builds their tree (empty when the file has no `o`/`g` line).
    pub fn new(text: &[u8]) -> Self {
        let mut out = Vec::with_capacity(text.len());
        let mut tree = NodeTree::default();
        let mut header_node = Vec::new();
        let mut by_name: HashMap<(Option<u32>, String), u32> = HashMap::new();
        let mut object: Option<u32> = None;
        for line in text.split_inclusive(|&b| b == b'\n') {
            let trimmed = line.trim_ascii_start();
            let kind = match trimmed.first() {
                Some(&k @ (b'o' | b'g')) if trimmed.get(1).is_none_or(|b| b.is_ascii_whitespace()) => k,
                _ => {
                    out.extend_from_slice(line);
                    continue;
                }
            };
            let mut name = String::from_utf8_lossy(trimmed[1..].trim_ascii()).into_owned();
            if name.is_empty() {
                name = "unnamed".into();
            }
            let parent = if kind == b'o' { None } else { object };
            let node = *by_name
                .entry((parent, name.clone()))
                .or_insert_with(|| tree.add(name, parent));
            if kind == b'o' {
                object = Some(node);
            }
            out.extend_from_slice(format!("o {TAG}{}\n", header_node.len()).as_bytes());
            header_node.push(node);
        }
        Self {
            text: out,
            tree,
            header_node,
        }
    }

    /// The tree node and display name of a tobj model named `model_name` (a tag, or tobj's own name for
    /// faces before any header).
    pub fn node_of(&mut self, model_name: &str) -> (u32, String) {
        let header = model_name
            .strip_prefix(TAG)
            .and_then(|k| k.parse::<usize>().ok())
            .and_then(|k| self.header_node.get(k).copied());
        let node = match header {
            Some(n) => n,
            None => {
                // Faces before the first header: one root node under tobj's name.
                let existing = self
                    .tree
                    .roots()
                    .find(|&r| self.tree.nodes[r as usize].name == model_name);
                existing.unwrap_or_else(|| self.tree.add(model_name, None))
            }
        };
        (node, self.tree.nodes[node as usize].name.clone())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn objects_own_groups_and_names_repeat() {
        let src =
            b"v 0 0 0\no Body\ng front\nf 1 1 1\ng back\no Lid\r\ng front\n  g  back \no Body\ng front\n";
        let mut t = TaggedObj::new(src);
        let text = String::from_utf8(t.text.clone()).unwrap();
        assert!(
            text.starts_with("v 0 0 0\no \u{1}0\no \u{1}1\nf 1 1 1\n"),
            "{text:?}"
        );
        let names: Vec<(&str, Option<u32>)> =
            t.tree.nodes.iter().map(|n| (n.name.as_str(), n.parent)).collect();
        assert_eq!(
            names,
            vec![
                ("Body", None),
                ("front", Some(0)),
                ("back", Some(0)),
                ("Lid", None),
                ("front", Some(3)),
                ("back", Some(3)),
            ]
        );
        // The second "o Body" and its "g front" reuse the first ones.
        assert_eq!(t.node_of("\u{1}6"), (0, "Body".into()));
        assert_eq!(t.node_of("\u{1}7"), (1, "front".into()));
        assert_eq!(t.node_of("\u{1}4"), (4, "front".into()));
        assert_eq!(t.node_of("unnamed_object"), (6, "unnamed_object".into()));
        assert_eq!(t.node_of("unnamed_object").0, 6);
        // A word starting with o/g is no header.
        assert_eq!(TaggedObj::new(b"gx 1\nobject\n").tree.len(), 0);
    }
}
