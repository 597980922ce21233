//! `math`: a binary operation on two numbers.

use cgnodes_api::prelude::*;

/// The operations `math` offers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MathOp {
    /// `a + b`.
    Add,
    /// `a - b`.
    Sub,
    /// `a * b`.
    Mul,
    /// `a / b`.
    Div,
    /// `a` to the power `b`.
    Pow,
    /// The smaller of `a` and `b`.
    Min,
    /// The larger of `a` and `b`.
    Max,
}

impl Choice for MathOp {
    const CHOICES: &'static [(&'static str, Self)] = &[
        ("add", MathOp::Add),
        ("sub", MathOp::Sub),
        ("mul", MathOp::Mul),
        ("div", MathOp::Div),
        ("pow", MathOp::Pow),
        ("min", MathOp::Min),
        ("max", MathOp::Max),
    ];
}

impl MathOp {
    /// The operation's socket name (`add`, `pow`, ...).
    pub fn name(self) -> &'static str {
        Self::CHOICES
            .iter()
            .find(|(_, op)| *op == self)
            .map_or("?", |(n, _)| n)
    }
}

/// Why `apply` has no result.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MathError {
    /// `a / 0`.
    #[error("division of {0} by zero")]
    DivisionByZero(f64),
    /// The result is NaN or infinite.
    #[error("{op}({a}, {b}) is not a finite number")]
    NotFinite {
        /// The operation's name.
        op: &'static str,
        /// First operand.
        a: f64,
        /// Second operand.
        b: f64,
    },
}

/// Applies `op` to `a` and `b`. Division by zero and non-finite results are errors.
pub fn apply(op: MathOp, a: f64, b: f64) -> Result<f64, MathError> {
    let r = match op {
        MathOp::Add => a + b,
        MathOp::Sub => a - b,
        MathOp::Mul => a * b,
        MathOp::Div => {
            if b == 0.0 {
                return Err(MathError::DivisionByZero(a));
            }
            a / b
        }
        MathOp::Pow => a.powf(b),
        MathOp::Min => a.min(b),
        MathOp::Max => a.max(b),
    };
    if r.is_finite() {
        Ok(r)
    } else {
        Err(MathError::NotFinite {
            op: op.name(),
            a,
            b,
        })
    }
}

fn declare(b: &mut NodeBuilder) {
    b.doc("Adds, subtracts, multiplies, divides, raises to a power, or takes min or max of two numbers.");
    b.add_input::<f64>("a").default(0.0);
    b.add_input::<f64>("b").default(0.0);
    b.add_choice::<MathOp>("op").doc("The operation.");
    b.add_output::<f64>("value");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let a: f64 = ctx.input("a")?;
    let b: f64 = ctx.input("b")?;
    let op = ctx.choice::<MathOp>("op")?;
    let v = apply(op, a, b).map_err(|e| NodeError::invalid("b", e.to_string()))?;
    ctx.set_output("value", v);
    Ok(())
}

/// Registers `math`.
pub fn register(r: &mut Registry) {
    r.add("math", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::{apply, MathOp};

    #[test]
    fn operations() {
        assert_eq!(apply(MathOp::Add, 2.0, 3.0), Ok(5.0));
        assert_eq!(apply(MathOp::Pow, 2.0, 10.0), Ok(1024.0));
        assert_eq!(apply(MathOp::Max, -1.0, 3.0), Ok(3.0));
        assert!(apply(MathOp::Div, 1.0, 0.0).is_err());
        let e = apply(MathOp::Pow, -1.0, 0.5).unwrap_err().to_string();
        assert!(e.starts_with("pow(-1, 0.5)"), "{e}");
    }
}
