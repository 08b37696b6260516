//! The model tree: the file's node hierarchy (glTF nodes, OBJ objects and groups) and which instances each
//! node owns. Instances stay a flat list (what the renderer draws); the tree only names and groups them.
//!
//! Invariant: a node's parent has a smaller id than the node (nodes are added in pre-order), so per-node
//! totals are one reverse pass and no walk can loop.

use crate::error::SceneError;

/// One node of the model tree.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Node {
    pub name: String,
    /// `None` for a root.
    pub parent: Option<u32>,
    pub children: Vec<u32>,
    /// Instances this node places itself (indices into `Scene::instances`), not those of its children.
    pub instances: Vec<u32>,
}

/// The node hierarchy of a scene; empty for generated scenes until [`NodeTree::single`] fills it.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct NodeTree {
    pub nodes: Vec<Node>,
}

impl NodeTree {
    /// One root node owning instances `0..count` (STL, PLY, generated scenes, OBJ without objects/groups).
    pub fn single(name: impl Into<String>, count: usize) -> Self {
        let mut t = Self::default();
        let root = t.add(name, None);
        t.nodes[root as usize].instances = (0..count as u32).collect();
        t
    }

    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// Adds a node under `parent` (which must exist) and returns its id.
    pub fn add(&mut self, name: impl Into<String>, parent: Option<u32>) -> u32 {
        let id = self.nodes.len() as u32;
        debug_assert!(parent.is_none_or(|p| p < id));
        if let Some(p) = parent {
            self.nodes[p as usize].children.push(id);
        }
        self.nodes.push(Node {
            name: name.into(),
            parent,
            ..Node::default()
        });
        id
    }

    /// Root nodes in order.
    pub fn roots(&self) -> impl Iterator<Item = u32> + '_ {
        self.nodes
            .iter()
            .enumerate()
            .filter(|(_, n)| n.parent.is_none())
            .map(|(i, _)| i as u32)
    }

    /// Instances in each node's subtree (its own and all descendants'), per node.
    pub fn instance_counts(&self) -> Vec<u64> {
        self.counts_where(|_| true)
    }

    /// Instances for which `keep` holds in each node's subtree, per node (e.g. the visible ones).
    pub fn counts_where(&self, keep: impl Fn(u32) -> bool) -> Vec<u64> {
        let mut counts: Vec<u64> = self
            .nodes
            .iter()
            .map(|n| n.instances.iter().filter(|&&i| keep(i)).count() as u64)
            .collect();
        for i in (0..self.nodes.len()).rev() {
            if let Some(p) = self.nodes[i].parent {
                counts[p as usize] += counts[i];
            }
        }
        counts
    }

    /// Every instance of the node's subtree, sorted (empty for an unknown node).
    pub fn subtree_instances(&self, node: u32) -> Vec<u32> {
        let mut out = Vec::new();
        let mut stack = vec![node];
        while let Some(n) = stack.pop() {
            let Some(node) = self.nodes.get(n as usize) else {
                continue;
            };
            out.extend_from_slice(&node.instances);
            stack.extend(node.children.iter().copied());
        }
        out.sort_unstable();
        out.dedup();
        out
    }

    /// The owning node of each of `count` instances (`None` if no node owns it).
    pub fn owners(&self, count: usize) -> Vec<Option<u32>> {
        let mut owner = vec![None; count];
        for (id, n) in self.nodes.iter().enumerate() {
            for &i in &n.instances {
                if let Some(o) = owner.get_mut(i as usize) {
                    *o = Some(id as u32);
                }
            }
        }
        owner
    }

    /// The node owning `instance`, if any.
    pub fn owner_of(&self, instance: u32) -> Option<u32> {
        self.nodes
            .iter()
            .position(|n| n.instances.contains(&instance))
            .map(|i| i as u32)
    }

    /// The path from a root to `node` (both included); empty for an unknown node.
    pub fn path(&self, node: u32) -> Vec<u32> {
        let mut path = Vec::new();
        let mut cur = Some(node).filter(|&n| (n as usize) < self.nodes.len());
        while let Some(n) = cur {
            path.push(n);
            cur = self.nodes[n as usize].parent;
        }
        path.reverse();
        path
    }

    /// Nodes whose name contains `query` (case-insensitive), in id order.
    pub fn search(&self, query: &str) -> Vec<u32> {
        let q = query.to_lowercase();
        self.nodes
            .iter()
            .enumerate()
            .filter(|(_, n)| n.name.to_lowercase().contains(&q))
            .map(|(i, _)| i as u32)
            .collect()
    }

    /// Drops nodes whose subtree owns no instance (cameras, lights, empty groups), keeping ids in pre-order.
    pub fn prune_empty(&mut self) {
        let counts = self.instance_counts();
        let mut new_id = vec![u32::MAX; self.nodes.len()];
        let mut kept = Vec::new();
        for (i, node) in std::mem::take(&mut self.nodes).into_iter().enumerate() {
            if counts[i] == 0 {
                continue;
            }
            new_id[i] = kept.len() as u32;
            kept.push(node);
        }
        for n in &mut kept {
            n.parent = n.parent.map(|p| new_id[p as usize]);
            n.children = n
                .children
                .iter()
                .map(|&c| new_id[c as usize])
                .filter(|&c| c != u32::MAX)
                .collect();
        }
        self.nodes = kept;
    }

    /// Instance `removed` left the scene: later instance ids shift down by one.
    pub(crate) fn instance_removed(&mut self, removed: u32) {
        for n in &mut self.nodes {
            n.instances.retain(|&i| i != removed);
            for i in &mut n.instances {
                if *i > removed {
                    *i -= 1;
                }
            }
        }
    }

    /// An instance was inserted at `at` (later ids shift up by one), owned by `owner` if given.
    pub(crate) fn instance_inserted(&mut self, at: u32, owner: Option<u32>) {
        for n in &mut self.nodes {
            for i in &mut n.instances {
                if *i >= at {
                    *i += 1;
                }
            }
        }
        if let Some(n) = owner.and_then(|o| self.nodes.get_mut(o as usize)) {
            let pos = n.instances.partition_point(|&i| i < at);
            n.instances.insert(pos, at);
        }
    }

    /// Checks the tree against `instances` instances: parents before children, children lists matching
    /// parents, instance ids in range and owned at most once.
    pub fn validate(&self, instances: usize) -> Result<(), SceneError> {
        let bad = |m: String| Err(SceneError::Invalid(format!("model tree: {m}")));
        let mut owned = vec![false; instances];
        for (id, n) in self.nodes.iter().enumerate() {
            if let Some(p) = n.parent {
                if p as usize >= id || !self.nodes[p as usize].children.contains(&(id as u32)) {
                    return bad(format!("node {id} has an inconsistent parent {p}"));
                }
            }
            for &c in &n.children {
                if self.nodes.get(c as usize).and_then(|c| c.parent) != Some(id as u32) {
                    return bad(format!("node {id} lists child {c} whose parent differs"));
                }
            }
            for &i in &n.instances {
                match owned.get_mut(i as usize) {
                    None => return bad(format!("node {id} owns instance {i} of {instances}")),
                    Some(true) => return bad(format!("instance {i} has two owning nodes")),
                    Some(o) => *o = true,
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// root(0) ─ a(1) ─ a1(2) [inst 0, 1]
    ///         └ b(3) [inst 2]
    /// other(4) [inst 3]
    fn tree() -> NodeTree {
        let mut t = NodeTree::default();
        let root = t.add("root", None);
        let a = t.add("a", Some(root));
        let a1 = t.add("a1", Some(a));
        let b = t.add("B", Some(root));
        let other = t.add("other", None);
        t.nodes[a1 as usize].instances = vec![0, 1];
        t.nodes[b as usize].instances = vec![2];
        t.nodes[other as usize].instances = vec![3];
        t
    }

    #[test]
    fn counts_paths_search_owners() {
        let t = tree();
        t.validate(4).unwrap();
        assert_eq!(t.instance_counts(), vec![3, 2, 2, 1, 1]);
        assert_eq!(t.counts_where(|i| i != 1), vec![2, 1, 1, 1, 1]);
        assert_eq!(t.subtree_instances(0), vec![0, 1, 2]);
        assert_eq!(t.subtree_instances(9), Vec::<u32>::new());
        assert_eq!(t.path(2), vec![0, 1, 2]);
        assert_eq!(t.roots().collect::<Vec<_>>(), vec![0, 4]);
        assert_eq!(t.search("b"), vec![3]);
        assert_eq!(t.search("A"), vec![1, 2]);
        assert_eq!(t.owners(5), vec![Some(2), Some(2), Some(3), Some(4), None]);
        assert_eq!(t.owner_of(2), Some(3));
    }

    #[test]
    fn removal_and_insertion_keep_ownership() {
        let mut t = tree();
        t.instance_removed(1);
        assert_eq!(t.nodes[2].instances, vec![0]);
        assert_eq!(t.nodes[3].instances, vec![1]);
        assert_eq!(t.nodes[4].instances, vec![2]);
        t.instance_inserted(1, Some(2));
        assert_eq!(t, tree());
    }

    #[test]
    fn prune_drops_empty_subtrees() {
        let mut t = tree();
        let empty = t.add("camera", Some(1));
        t.add("light", Some(empty));
        t.prune_empty();
        assert_eq!(t, tree());
        assert!(t.validate(3).is_err(), "instance 3 out of range");
    }
}
