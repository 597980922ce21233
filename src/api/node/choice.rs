//! Choice sockets: a string socket that accepts one of a closed set of names (an enum
//! parameter such as Tutte's `weights`). The names are declared and parsed from one table, so
//! what `cgnodes describe` lists, what validation accepts and what a node runs never disagree.

use super::{ExecContext, NodeBuilder, NodeError, SocketBuilder};

/// A closed set of names a string socket accepts, each naming one value of `Self`.
pub trait Choice: Copy + 'static {
    /// Every accepted name with its value; the first is the socket's default.
    const CHOICES: &'static [(&'static str, Self)];

    /// The value named `name`, if it is one of `CHOICES`.
    fn from_name(name: &str) -> Option<Self> {
        Self::CHOICES
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(_, v)| *v)
    }

    /// Every accepted name, in declaration order.
    fn names() -> Vec<&'static str> {
        Self::CHOICES.iter().map(|(n, _)| *n).collect()
    }
}

/// Parses `name` as a `C`, with the error validation gives for a literal outside the choices.
pub fn parse_choice<C: Choice>(socket: &str, name: &str) -> Result<C, NodeError> {
    C::from_name(name).ok_or_else(|| {
        NodeError::invalid(
            socket,
            format!("'{name}' is not one of {}", C::names().join(", ")),
        )
    })
}

impl SocketBuilder<'_> {
    /// Restricts a string socket to the names of `C` (the first is the default unless one is set).
    pub fn choice<C: Choice>(self) -> Self {
        self.choices(&C::names())
    }
}

impl NodeBuilder {
    /// Adds a string input that accepts the names of `C`; read it with `ExecContext::choice`.
    pub fn add_choice<C: Choice>(&mut self, name: &str) -> SocketBuilder<'_> {
        self.add_input::<String>(name).choice::<C>()
    }
}

impl ExecContext<'_> {
    /// Reads choice input `name` as a `C` (an unknown name is an invalid-input error on it).
    pub fn choice<C: Choice>(&self, name: &str) -> Result<C, NodeError> {
        parse_choice(name, &self.input::<String>(name)?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Clone, Copy, Debug, PartialEq)]
    enum Shape {
        Circle,
        Square,
    }

    impl Choice for Shape {
        const CHOICES: &'static [(&'static str, Self)] =
            &[("circle", Shape::Circle), ("square", Shape::Square)];
    }

    #[test]
    fn names_parse_to_their_values_and_others_are_refused_by_socket() {
        assert_eq!(Shape::from_name("square"), Some(Shape::Square));
        assert_eq!(
            parse_choice::<Shape>("boundary", "circle").unwrap(),
            Shape::Circle
        );
        let e = parse_choice::<Shape>("boundary", "disk").unwrap_err();
        assert_eq!(e.socket.as_deref(), Some("boundary"));
        assert!(
            e.message.contains("'disk' is not one of circle, square"),
            "{}",
            e.message
        );
        let mut b = NodeBuilder::new("t");
        b.add_choice::<Shape>("boundary");
        let d = b.build(std::sync::Arc::new(|_: &mut ExecContext| Ok(())));
        let s = d.input("boundary").unwrap();
        assert_eq!(
            s.choices.as_deref(),
            Some(&["circle".to_string(), "square".to_string()][..])
        );
        assert_eq!(s.default, Some(serde_json::json!("circle")));
    }
}
