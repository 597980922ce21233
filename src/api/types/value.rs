use super::*;
use serde::{Deserialize, Serialize};
use std::fmt;
use std::sync::Arc;

/// The type of a socket. Checked when a graph is validated, before anything runs.
#[derive(Clone, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum SocketType {
    Bool,
    Int,
    Float,
    String,
    Vec2,
    Vec3,
    Color,
    Mesh,
    Image,
    Points,
    Camera,
    Light,
    Material,
    Scene,
    Curve,
    Skeleton,
    Table,
    /// A trained classifier.
    Model,
    /// A list of values of one type; a list input accepts several links.
    List(Box<SocketType>),
    /// Accepts any value (used by `print` and `table_write`).
    Any,
}

impl fmt::Display for SocketType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SocketType::List(t) => write!(f, "list<{t}>"),
            other => {
                let s = serde_json::to_value(other).unwrap_or_default();
                write!(f, "{}", s.as_str().unwrap_or("?"))
            }
        }
    }
}

impl SocketType {
    /// Whether a value of type `from` may feed a socket of this type, possibly by an implicit
    /// conversion (Int to Float, Float to Vec3 or Color, Mesh to Scene, T to list<T>).
    pub fn accepts(&self, from: &SocketType) -> bool {
        use SocketType as T;
        if self == from || *self == T::Any {
            return true;
        }
        match (self, from) {
            (T::Float, T::Int) => true,
            (T::Vec2 | T::Vec3 | T::Color, T::Int | T::Float) => true,
            (T::Color, T::Vec3) | (T::Vec3, T::Color) => true,
            (T::Scene, T::Mesh) => true,
            (T::List(inner), x) => inner.accepts(x),
            _ => false,
        }
    }
}

/// An RGB colour in linear space.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Color(pub [f64; 3]);

/// A value on a socket.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub enum Value {
    Bool(bool),
    Int(i64),
    Float(f64),
    String(String),
    Vec2([f64; 2]),
    Vec3([f64; 3]),
    Color([f64; 3]),
    Mesh(Arc<Mesh>),
    Image(Arc<Image>),
    Points(Arc<Points>),
    Camera(Arc<Camera>),
    Light(Arc<Light>),
    Material(Arc<Material>),
    Scene(Arc<Scene>),
    Curve(Arc<Curve>),
    Skeleton(Arc<Skeleton>),
    Table(Arc<Table>),
    Model(Arc<Model>),
    List(Arc<Vec<Value>>),
}

impl Value {
    /// The socket type this value has.
    pub fn socket_type(&self) -> SocketType {
        use SocketType as T;
        match self {
            Value::Bool(_) => T::Bool,
            Value::Int(_) => T::Int,
            Value::Float(_) => T::Float,
            Value::String(_) => T::String,
            Value::Vec2(_) => T::Vec2,
            Value::Vec3(_) => T::Vec3,
            Value::Color(_) => T::Color,
            Value::Mesh(_) => T::Mesh,
            Value::Image(_) => T::Image,
            Value::Points(_) => T::Points,
            Value::Camera(_) => T::Camera,
            Value::Light(_) => T::Light,
            Value::Material(_) => T::Material,
            Value::Scene(_) => T::Scene,
            Value::Curve(_) => T::Curve,
            Value::Skeleton(_) => T::Skeleton,
            Value::Table(_) => T::Table,
            Value::Model(_) => T::Model,
            Value::List(items) => T::List(Box::new(
                items.first().map(|v| v.socket_type()).unwrap_or(T::Any),
            )),
        }
    }

    /// Converts this value to `target`, applying the implicit conversions users expect.
    /// Returns `None` when no conversion exists.
    pub fn convert_to(&self, target: &SocketType) -> Option<Value> {
        use SocketType as T;
        if *target == T::Any || self.socket_type() == *target {
            return Some(self.clone());
        }
        Some(match (target, self) {
            (T::Float, Value::Int(i)) => Value::Float(*i as f64),
            (T::Vec2, Value::Float(x)) => Value::Vec2([*x; 2]),
            (T::Vec2, Value::Int(x)) => Value::Vec2([*x as f64; 2]),
            (T::Vec3, Value::Float(x)) => Value::Vec3([*x; 3]),
            (T::Vec3, Value::Int(x)) => Value::Vec3([*x as f64; 3]),
            (T::Color, Value::Float(x)) => Value::Color([*x; 3]),
            (T::Color, Value::Int(x)) => Value::Color([*x as f64; 3]),
            (T::Color, Value::Vec3(x)) => Value::Color(*x),
            (T::Vec3, Value::Color(x)) => Value::Vec3(*x),
            (T::Scene, Value::Mesh(m)) => Value::Scene(Arc::new(Scene::from_mesh(m.clone()))),
            (T::List(inner), Value::List(items)) => Value::List(Arc::new(
                items
                    .iter()
                    .map(|v| v.convert_to(inner))
                    .collect::<Option<Vec<_>>>()?,
            )),
            (T::List(inner), v) => Value::List(Arc::new(vec![v.convert_to(inner)?])),
            _ => return None,
        })
    }

    /// Parses a literal given in a graph's `params` (or on the command line with `--set`)
    /// for a socket of type `ty`. Only plain types have literals.
    pub fn from_json(ty: &SocketType, j: &serde_json::Value) -> Result<Value, String> {
        use serde_json::Value as J;
        use SocketType as T;
        let num = |j: &J| {
            j.as_f64()
                .ok_or_else(|| format!("expected a number, got {j}"))
        };
        let arr = |j: &J, n: usize| -> Result<Vec<f64>, String> {
            match j {
                J::Array(a) if a.len() == n => a.iter().map(num).collect(),
                J::Number(_) => Ok(vec![num(j)?; n]),
                _ => Err(format!("expected an array of {n} numbers, got {j}")),
            }
        };
        Ok(match ty {
            T::Bool => Value::Bool(
                j.as_bool()
                    .ok_or_else(|| format!("expected true or false, got {j}"))?,
            ),
            T::Int => match j {
                J::Number(n) if n.is_i64() => Value::Int(n.as_i64().unwrap_or_default()),
                J::Number(n)
                    if n.as_f64()
                        .is_some_and(|f| f.fract() == 0.0 && f.abs() < 9e15) =>
                {
                    Value::Int(n.as_f64().unwrap_or_default() as i64)
                }
                _ => return Err(format!("expected an integer, got {j}")),
            },
            T::Float => {
                let x = num(j)?;
                if !x.is_finite() {
                    return Err(format!("expected a finite number, got {j}"));
                }
                Value::Float(x)
            }
            T::String => Value::String(
                j.as_str()
                    .ok_or_else(|| format!("expected a string, got {j}"))?
                    .to_string(),
            ),
            T::Vec2 => {
                let a = arr(j, 2)?;
                Value::Vec2([a[0], a[1]])
            }
            T::Vec3 => {
                let a = arr(j, 3)?;
                Value::Vec3([a[0], a[1], a[2]])
            }
            T::Color => {
                let a = arr(j, 3)?;
                Value::Color([a[0], a[1], a[2]])
            }
            T::List(inner) => match j {
                J::Array(a) => Value::List(Arc::new(
                    a.iter()
                        .map(|x| Value::from_json(inner, x))
                        .collect::<Result<_, _>>()?,
                )),
                other => Value::List(Arc::new(vec![Value::from_json(inner, other)?])),
            },
            T::Any => match j {
                J::Bool(b) => Value::Bool(*b),
                J::Number(n) if n.is_i64() => Value::Int(n.as_i64().unwrap_or_default()),
                J::Number(n) => Value::Float(n.as_f64().unwrap_or_default()),
                J::String(s) => Value::String(s.clone()),
                _ => return Err(format!("no literal form for {j}")),
            },
            other => return Err(format!("a {other} socket takes a link, not a literal")),
        })
    }

    /// The literal as JSON (for plain values), used for cache keys, `describe` and plugins.
    pub fn to_json(&self) -> Option<serde_json::Value> {
        use serde_json::json;
        Some(match self {
            Value::Bool(b) => json!(b),
            Value::Int(i) => json!(i),
            Value::Float(f) => json!(f),
            Value::String(s) => json!(s),
            Value::Vec2(v) => json!(v),
            Value::Vec3(v) | Value::Color(v) => json!(v),
            Value::List(items) => {
                serde_json::Value::Array(items.iter().map(|v| v.to_json()).collect::<Option<_>>()?)
            }
            _ => return None,
        })
    }

    /// A short human description (for `print` and logs).
    pub fn summary(&self) -> String {
        match self {
            Value::Mesh(m) => format!(
                "mesh: {} vertices, {} faces",
                m.positions.len(),
                m.num_faces()
            ),
            Value::Image(i) => format!("image: {}x{}", i.width, i.height),
            Value::Points(p) => format!("points: {} ({}-D)", p.positions.len(), p.dim),
            Value::Model(m) => format!(
                "model: {}, layers {:?}, classes {:?}",
                m.kind,
                m.layers.iter().map(|l| l.outputs).collect::<Vec<_>>(),
                m.classes
            ),
            Value::Table(t) => {
                let mut s = String::new();
                for (name, col) in &t.columns {
                    s.push_str(&format!("{name}: {:?}\n", col.last()));
                }
                format!(
                    "table: {} columns, {} rows\n{}",
                    t.columns.len(),
                    t.num_rows(),
                    s.trim_end()
                )
            }
            Value::Scene(s) => format!(
                "scene: {} objects, {} lights",
                s.objects.len(),
                s.lights.len()
            ),
            other => match other.to_json() {
                Some(j) => j.to_string(),
                None => format!("{}", other.socket_type()),
            },
        }
    }
}

/// Rust types that a socket can be declared with (`b.add_input::<Mesh>("mesh")`).
pub trait Typed {
    /// The socket type.
    fn socket_type() -> SocketType;
}

/// Rust types that a node can read from an input socket (`ctx.input::<Arc<Mesh>>("mesh")`).
pub trait FromValue: Sized {
    /// Extracts the value, or `None` when it has another type.
    fn from_value(v: &Value) -> Option<Self>;
}

macro_rules! plain {
    ($t:ty, $st:ident, $var:ident) => {
        impl Typed for $t {
            fn socket_type() -> SocketType {
                SocketType::$st
            }
        }
        impl FromValue for $t {
            fn from_value(v: &Value) -> Option<Self> {
                match v {
                    Value::$var(x) => Some(x.clone()),
                    _ => None,
                }
            }
        }
        impl From<$t> for Value {
            fn from(x: $t) -> Value {
                Value::$var(x)
            }
        }
    };
}
plain!(bool, Bool, Bool);
plain!(i64, Int, Int);
plain!(f64, Float, Float);
plain!(String, String, String);
plain!([f64; 2], Vec2, Vec2);
plain!([f64; 3], Vec3, Vec3);

impl Typed for Color {
    fn socket_type() -> SocketType {
        SocketType::Color
    }
}
impl FromValue for Color {
    fn from_value(v: &Value) -> Option<Self> {
        match v {
            Value::Color(c) | Value::Vec3(c) => Some(Color(*c)),
            _ => None,
        }
    }
}
impl From<Color> for Value {
    fn from(c: Color) -> Value {
        Value::Color(c.0)
    }
}
impl From<&str> for Value {
    fn from(s: &str) -> Value {
        Value::String(s.to_string())
    }
}

macro_rules! shared {
    ($t:ident) => {
        impl Typed for $t {
            fn socket_type() -> SocketType {
                SocketType::$t
            }
        }
        impl FromValue for Arc<$t> {
            fn from_value(v: &Value) -> Option<Self> {
                match v {
                    Value::$t(x) => Some(x.clone()),
                    _ => None,
                }
            }
        }
        impl From<Arc<$t>> for Value {
            fn from(x: Arc<$t>) -> Value {
                Value::$t(x)
            }
        }
        impl From<$t> for Value {
            fn from(x: $t) -> Value {
                Value::$t(Arc::new(x))
            }
        }
    };
}
shared!(Mesh);
shared!(Image);
shared!(Points);
shared!(Camera);
shared!(Light);
shared!(Material);
shared!(Scene);
shared!(Curve);
shared!(Skeleton);
shared!(Table);
shared!(Model);

impl<T: Typed> Typed for Vec<T> {
    fn socket_type() -> SocketType {
        SocketType::List(Box::new(T::socket_type()))
    }
}
impl<T: FromValue> FromValue for Vec<T> {
    fn from_value(v: &Value) -> Option<Self> {
        match v {
            Value::List(items) => items.iter().map(T::from_value).collect(),
            other => Some(vec![T::from_value(other)?]),
        }
    }
}
impl<T: Into<Value>> From<Vec<T>> for Value {
    fn from(items: Vec<T>) -> Value {
        Value::List(Arc::new(items.into_iter().map(Into::into).collect()))
    }
}

/// Any value: for sockets declared `Any`.
impl FromValue for Value {
    fn from_value(v: &Value) -> Option<Self> {
        Some(v.clone())
    }
}
/// Marker type for `b.add_input::<AnyValue>("value")`.
pub struct AnyValue;
impl Typed for AnyValue {
    fn socket_type() -> SocketType {
        SocketType::Any
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn implicit_conversions() {
        assert!(SocketType::Float.accepts(&SocketType::Int));
        assert!(SocketType::Scene.accepts(&SocketType::Mesh));
        assert!(!SocketType::Mesh.accepts(&SocketType::Image));
        assert!(!SocketType::Int.accepts(&SocketType::Float));
        let v = Value::Int(3).convert_to(&SocketType::Vec3).unwrap();
        assert!(matches!(v, Value::Vec3([a, b, c]) if a == 3.0 && b == 3.0 && c == 3.0));
        assert!(Value::Float(1.5).convert_to(&SocketType::Int).is_none());
    }

    #[test]
    fn literals_parse_by_type() {
        let j: serde_json::Value = serde_json::json!([1, 2, 3]);
        assert!(matches!(
            Value::from_json(&SocketType::Vec3, &j),
            Ok(Value::Vec3(_))
        ));
        assert!(Value::from_json(&SocketType::Int, &serde_json::json!(2.5)).is_err());
        assert!(Value::from_json(&SocketType::Mesh, &serde_json::json!("x")).is_err());
        assert_eq!(
            SocketType::List(Box::new(SocketType::Mesh)).to_string(),
            "list<mesh>"
        );
    }
}
