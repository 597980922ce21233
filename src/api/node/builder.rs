//! `NodeBuilder`: how a node's `declare` function builds its `NodeDecl`
//! (`b.add_input::<Mesh>("mesh").doc(...)`).

use super::{ExecFn, FileRole, NodeDecl, SocketDecl};
use crate::types::{SocketType, Typed, Value};

/// Builds a `NodeDecl` (`b.add_input::<Mesh>("mesh")`).
pub struct NodeBuilder {
    decl: NodeDecl,
}

/// Sets the details of one socket; returned by `add_input` and `add_output`.
pub struct SocketBuilder<'a> {
    s: &'a mut SocketDecl,
}

impl<'a> SocketBuilder<'a> {
    /// The value used when the graph gives none.
    pub fn default(self, v: impl Into<Value>) -> Self {
        self.s.default = v.into().to_json();
        self
    }
    /// The accepted range, inclusive.
    pub fn range(self, min: f64, max: f64) -> Self {
        self.s.min = Some(min);
        self.s.max = Some(max);
        self
    }
    /// The smallest accepted value.
    pub fn min(self, min: f64) -> Self {
        self.s.min = Some(min);
        self
    }
    /// The largest accepted value.
    pub fn max(self, max: f64) -> Self {
        self.s.max = Some(max);
        self
    }
    /// The accepted strings; the first is the default unless one is set.
    pub fn choices(self, c: &[&str]) -> Self {
        self.s.choices = Some(c.iter().map(|x| x.to_string()).collect());
        if self.s.default.is_none() {
            self.s.default = c.first().map(|x| serde_json::json!(x));
        }
        self
    }
    /// One-line description.
    pub fn doc(self, d: &str) -> Self {
        self.s.doc = d.to_string();
        self
    }
    /// May be left unconnected; the node then sees `None` from `input_opt`.
    pub fn optional(self) -> Self {
        self.s.optional = true;
        self
    }
    /// The string names a file to read.
    pub fn file_in(self) -> Self {
        self.s.file = FileRole::Input;
        self
    }
    /// The string names a file to write under the output directory.
    pub fn file_out(self) -> Self {
        self.s.file = FileRole::Output;
        self
    }
}

impl NodeBuilder {
    /// A builder for node type `type_name`.
    pub fn new(type_name: &str) -> NodeBuilder {
        NodeBuilder {
            decl: NodeDecl {
                type_name: type_name.to_string(),
                doc: String::new(),
                category: String::new(),
                inputs: Vec::new(),
                outputs: Vec::new(),
                stateful: false,
                time_dependent: false,
                sink: false,
                source: "builtin".into(),
                exec: None,
                companions: None,
            },
        }
    }
    /// One-line description of the node.
    pub fn doc(&mut self, d: &str) -> &mut Self {
        self.decl.doc = d.to_string();
        self
    }
    /// Domain the node belongs to.
    pub fn category(&mut self, c: &str) -> &mut Self {
        self.decl.category = c.to_string();
        self
    }
    /// Adds an input socket of type `T`.
    pub fn add_input<T: Typed>(&mut self, name: &str) -> SocketBuilder<'_> {
        self.add_input_of(name, T::socket_type())
    }
    /// Adds an input socket of a type known only at run time (plugins).
    pub fn add_input_of(&mut self, name: &str, ty: SocketType) -> SocketBuilder<'_> {
        push_socket(&mut self.decl.inputs, name, ty)
    }
    /// Adds an output socket of type `T`.
    pub fn add_output<T: Typed>(&mut self, name: &str) -> SocketBuilder<'_> {
        self.add_output_of(name, T::socket_type())
    }
    /// Adds an output socket of a type known only at run time.
    pub fn add_output_of(&mut self, name: &str, ty: SocketType) -> SocketBuilder<'_> {
        push_socket(&mut self.decl.outputs, name, ty)
    }
    /// Keeps state between frames and runs every frame.
    pub fn stateful(&mut self) -> &mut Self {
        self.decl.stateful = true;
        self.decl.time_dependent = true;
        self
    }
    /// Reads the frame number.
    pub fn time_dependent(&mut self) -> &mut Self {
        self.decl.time_dependent = true;
        self
    }
    /// Has an effect outside the graph (writes a file, prints): evaluated by default.
    pub fn sink(&mut self) -> &mut Self {
        self.decl.sink = true;
        self
    }
    /// Names the further files the node reads because of an input file (`f(path)`, for
    /// example `cache::obj_companions`), so that the cache key stamps them too.
    pub fn companions(&mut self, f: super::decl::CompanionFn) -> &mut Self {
        self.decl.companions = Some(f);
        self
    }
    /// Where the node comes from (default `builtin`).
    pub fn source(&mut self, s: &str) -> &mut Self {
        self.decl.source = s.to_string();
        self
    }
    /// The finished declaration.
    pub fn build(mut self, exec: ExecFn) -> NodeDecl {
        self.decl.exec = Some(exec);
        self.decl
    }
}

/// Appends a new socket to `list` and returns its builder.
fn push_socket<'a>(list: &'a mut Vec<SocketDecl>, name: &str, ty: SocketType) -> SocketBuilder<'a> {
    list.push(socket(name, ty));
    SocketBuilder {
        s: list.last_mut().expect("just pushed"),
    }
}

fn socket(name: &str, ty: SocketType) -> SocketDecl {
    SocketDecl {
        name: name.to_string(),
        ty,
        doc: String::new(),
        default: None,
        min: None,
        max: None,
        choices: None,
        optional: false,
        file: FileRole::None,
    }
}
