//! `math`: a binary operation on two numbers.

use crate::prelude::*;

/// The operations `math` offers.
pub const OPS: &[&str] = &["add", "sub", "mul", "div", "pow", "min", "max"];

/// Applies `op` to `a` and `b`. Division by zero and non-finite results are errors.
pub fn apply(op: &str, a: f64, b: f64) -> Result<f64, String> {
    let r = match op {
        "add" => a + b,
        "sub" => a - b,
        "mul" => a * b,
        "div" => {
            if b == 0.0 {
                return Err(format!("division of {a} by zero"));
            }
            a / b
        }
        "pow" => a.powf(b),
        "min" => a.min(b),
        "max" => a.max(b),
        other => return Err(format!("unknown operation '{other}'")),
    };
    if r.is_finite() {
        Ok(r)
    } else {
        Err(format!("{op}({a}, {b}) is not a finite number"))
    }
}

fn declare(b: &mut NodeBuilder) {
    b.doc("Adds, subtracts, multiplies, divides, raises to a power, or takes min or max of two numbers.");
    b.add_input::<f64>("a").default(0.0);
    b.add_input::<f64>("b").default(0.0);
    b.add_input::<String>("op")
        .choices(OPS)
        .doc("The operation.");
    b.add_output::<f64>("value");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let a: f64 = ctx.input("a")?;
    let b: f64 = ctx.input("b")?;
    let op: String = ctx.input("op")?;
    let v = apply(&op, a, b).map_err(|e| NodeError::invalid("b", e))?;
    ctx.set_output("value", v);
    Ok(())
}

/// Registers `math`.
pub fn register(r: &mut Registry) {
    r.add("math", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::apply;

    #[test]
    fn operations() {
        assert_eq!(apply("add", 2.0, 3.0), Ok(5.0));
        assert_eq!(apply("pow", 2.0, 10.0), Ok(1024.0));
        assert_eq!(apply("max", -1.0, 3.0), Ok(3.0));
        assert!(apply("div", 1.0, 0.0).is_err());
        assert!(apply("pow", -1.0, 0.5).is_err());
    }
}
