//! The registry of node types. Built-in nodes register through the same calls a plugin uses;
//! the registry of every built-in node is assembled in `nodes::builtin_registry`.

use crate::node::{ExecContext, NodeBuilder, NodeDecl, NodeError};
use crate::types::{Image, Mesh};
use std::collections::BTreeMap;
use std::sync::Arc;

/// All node types a graph may use, by name, and the mesh services the run report borrows
/// from the families that registered them.
#[derive(Clone, Default)]
pub struct Registry {
    nodes: BTreeMap<String, Arc<NodeDecl>>,
    /// Category given to nodes added through `add` (set by `with_category`).
    category: Option<String>,
    /// Mesh reading and previews for the run report; empty when no family provides them.
    pub mesh_hooks: MeshHooks,
}

/// What the run report needs from the render family (drawing a written mesh's thumbnail).
/// Whoever assembles the registry sets it, so the runtime shows meshes without depending on
/// any family; left `None`, the report links the mesh file instead of drawing it.
#[derive(Clone, Copy, Default)]
pub struct MeshHooks {
    /// Draws a mesh at `width` x `height`, framed on the bounds of another (a sequence's
    /// first frame, so a moving mesh moves in the frame), as a linear RGBA image.
    pub preview: Option<MeshPreviewFn>,
}

/// Draws the second mesh framed on the first's bounds (see `MeshHooks::preview`).
pub type MeshPreviewFn = fn(&Mesh, &Arc<Mesh>, u32, u32) -> Result<Image, String>;

impl Registry {
    /// An empty registry.
    pub fn new() -> Registry {
        Registry::default()
    }

    /// Runs `register` with `category` as the category of every node it adds through `add`
    /// (a domain sets it once, from its folder name; a node's `declare` may still override it).
    pub fn with_category(&mut self, category: &str, register: impl FnOnce(&mut Registry)) {
        let outer = self.category.replace(category.to_string());
        register(self);
        self.category = outer;
    }

    /// Registers a node from its declaration and execution functions (the usual way).
    pub fn add(
        &mut self,
        type_name: &str,
        declare: impl FnOnce(&mut NodeBuilder),
        execute: impl Fn(&mut ExecContext) -> Result<(), NodeError> + Send + Sync + 'static,
    ) {
        let mut b = NodeBuilder::new(type_name);
        if let Some(c) = &self.category {
            b.category(c);
        }
        declare(&mut b);
        self.add_decl(b.build(Arc::new(execute)));
    }

    /// Registers a finished declaration; a later registration of the same name replaces it.
    pub fn add_decl(&mut self, decl: NodeDecl) {
        self.nodes.insert(decl.type_name.clone(), Arc::new(decl));
    }

    /// The declaration of `type_name`.
    pub fn get(&self, type_name: &str) -> Option<&Arc<NodeDecl>> {
        self.nodes.get(type_name)
    }

    /// All declarations, sorted by name.
    pub fn iter(&self) -> impl Iterator<Item = &Arc<NodeDecl>> {
        self.nodes.values()
    }

    /// Number of node types.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// Whether no node type is registered.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// The registered name closest to `name`, for "did you mean" hints.
    pub fn closest(&self, name: &str) -> Option<String> {
        closest(name, self.nodes.keys().map(String::as_str))
    }
}

/// The candidate closest to `name` by Levenshtein distance, if reasonably close (within
/// half the longer name's length, and at least 2).
pub fn closest<'a>(name: &str, candidates: impl Iterator<Item = &'a str>) -> Option<String> {
    candidates
        .map(|c| (strsim::levenshtein(name, c), c))
        .filter(|(d, c)| *d <= (c.len().max(name.len()) / 2).max(2))
        .min()
        .map(|(_, c)| c.to_string())
}

#[cfg(test)]
mod tests {
    use super::Registry;

    #[test]
    fn with_category_sets_the_category_of_nodes_added_inside() {
        let mut r = Registry::new();
        r.with_category("param", |r| {
            r.add("a", |_| {}, |_| Ok(()));
            r.add(
                "b",
                |b| {
                    b.category("other");
                },
                |_| Ok(()),
            );
        });
        r.add("c", |_| {}, |_| Ok(()));
        assert_eq!(r.get("a").unwrap().category, "param");
        assert_eq!(r.get("b").unwrap().category, "other");
        assert_eq!(r.get("c").unwrap().category, "");
    }

    #[test]
    fn suggests_close_names() {
        let names = ["mesh_load", "mesh_save", "tutte"];
        assert_eq!(
            super::closest("mesh_lod", names.iter().copied()).as_deref(),
            Some("mesh_load")
        );
        assert_eq!(super::closest("zzzzzzzzzz", names.iter().copied()), None);
    }
}
