//! The USDA layer tree: prims (`def`/`over`/`class`) with their typed attributes,
//! relationships and metadata, parsed from text. Schema-agnostic so that mesh reading and
//! (later) skeleton reading share it; typed access to values is in `access`.

use super::error::UsdaError;
use super::lexer::{err, show, Lexer, Tok};

/// A parsed USDA value.
#[derive(Clone, Debug, PartialEq)]
pub enum UsdValue {
    /// A number.
    Num(f64),
    /// A quoted string.
    Str(String),
    /// A bare word (token, `None`, `true`).
    Ident(String),
    /// A path `<...>`.
    Path(String),
    /// `[ ... ]`.
    List(Vec<UsdValue>),
    /// `( ... )`.
    Tuple(Vec<UsdValue>),
    /// `{ key: value, ... }` (time samples).
    Dict(Vec<(UsdValue, UsdValue)>),
}

/// One attribute or relationship of a prim.
#[derive(Clone, Debug)]
pub struct UsdAttr {
    /// Name, e.g. `primvars:UVMap` or `rotations.timeSamples`.
    pub name: String,
    /// Value type, e.g. `point3f[]` (`rel` for relationships).
    pub type_name: String,
    /// Assigned value, if any.
    pub value: Option<UsdValue>,
    /// Metadata in parentheses after the value (`interpolation`, `elementSize`).
    pub meta: Vec<(String, UsdValue)>,
    /// Line of the declaration (1-based).
    pub line: usize,
}

/// One prim with its attributes and children.
#[derive(Clone, Debug)]
pub struct UsdPrim {
    /// `def`, `over` or `class`.
    pub specifier: String,
    /// Schema type (`Mesh`, `Xform`, ...), empty when untyped.
    pub type_name: String,
    /// Prim name.
    pub name: String,
    /// Absolute path, e.g. `/Balls/Balls`.
    pub path: String,
    /// Attributes and relationships in file order.
    pub attrs: Vec<UsdAttr>,
    /// Child prims.
    pub children: Vec<UsdPrim>,
    /// Line of the `def`.
    pub line: usize,
}

impl UsdPrim {
    /// The attribute called `name`.
    pub fn attr(&self, name: &str) -> Option<&UsdAttr> {
        self.attrs.iter().find(|a| a.name == name)
    }
}

/// A parsed layer: its metadata and root prims.
#[derive(Clone, Debug, Default)]
pub struct UsdLayer {
    /// Layer metadata (`defaultPrim`, `upAxis`, ...).
    pub meta: Vec<(String, UsdValue)>,
    /// Root prims.
    pub prims: Vec<UsdPrim>,
}

// One match over the value grammar (number, string, path, list, tuple, dictionary): long but flat.
fn parse_value(lx: &mut Lexer) -> Result<UsdValue, UsdaError> {
    let (t, line) = lx.expect_next("a value")?;
    Ok(match t {
        Tok::Num(v) => UsdValue::Num(v),
        Tok::Str(s) => UsdValue::Str(s),
        Tok::Path(p) => UsdValue::Path(p),
        Tok::Ident(s) => {
            let low = s.to_ascii_lowercase();
            if low == "nan" || low == "inf" || low == "infinity" {
                return Err(err(line, format!("'{s}' is not a finite number")));
            }
            UsdValue::Ident(s)
        }
        Tok::Punct(open @ (b'[' | b'(')) => {
            lx.enter(line)?;
            let close = if open == b'[' { b']' } else { b')' };
            let mut items = Vec::new();
            loop {
                if lx.is_punct(close)? {
                    lx.next()?;
                    break;
                }
                items.push(parse_value(lx)?);
                let (t, l) = lx.expect_next("',' or a closing bracket")?;
                match t {
                    Tok::Punct(b',') => {}
                    Tok::Punct(c) if c == close => break,
                    other => {
                        return Err(err(
                            l,
                            format!(
                                "expected ',' or '{}', found {}",
                                close as char,
                                show(&other)
                            ),
                        ))
                    }
                }
            }
            lx.leave();
            if open == b'[' {
                UsdValue::List(items)
            } else {
                UsdValue::Tuple(items)
            }
        }
        Tok::Punct(b'{') => {
            lx.enter(line)?;
            let mut items = Vec::new();
            if matches!(lx.peek()?, Some((Tok::Ident(_), _))) {
                // A typed dictionary (`customData = { dictionary Blender = { bool generated = 1 } }`).
                return parse_typed_dict(lx);
            }
            loop {
                if lx.is_punct(b'}')? {
                    lx.next()?;
                    break;
                }
                let (k, l) = lx.expect_next("a time sample key")?;
                let key = match k {
                    Tok::Num(v) => UsdValue::Num(v),
                    Tok::Str(s) => UsdValue::Str(s),
                    // A dictionary entry `TYPE NAME = VALUE` (Blender's `customData`).
                    Tok::Ident(_) => match lx.expect_next("a dictionary key")? {
                        (Tok::Ident(s) | Tok::Str(s), _) => {
                            lx.expect_punct(b'=')?;
                            let v = parse_value(lx)?;
                            items.push((UsdValue::Str(s), v));
                            if lx.is_punct(b',')? || lx.is_punct(b';')? {
                                lx.next()?;
                            }
                            continue;
                        }
                        (other, l) => {
                            return Err(err(
                                l,
                                format!("expected a dictionary key, found {}", show(&other)),
                            ))
                        }
                    },
                    other => {
                        return Err(err(
                            l,
                            format!(
                                "expected a time code in a timeSamples dictionary, found {} (dictionaries are not supported)",
                                show(&other)
                            ),
                        ))
                    }
                };
                lx.expect_punct(b':')?;
                let v = parse_value(lx)?;
                items.push((key, v));
                if lx.is_punct(b',')? {
                    lx.next()?;
                }
            }
            lx.leave();
            UsdValue::Dict(items)
        }
        other => {
            return Err(err(
                line,
                format!("expected a value, found {}", show(&other)),
            ))
        }
    })
}

/// Metadata in parentheses: `key = value` items, list edits (`prepend`, `append`, ...)
/// and a bare doc string.
fn parse_meta(lx: &mut Lexer) -> Result<Vec<(String, UsdValue)>, UsdaError> {
    lx.expect_punct(b'(')?;
    let mut out = Vec::new();
    loop {
        let (t, line) = lx.expect_next("metadata or ')'")?;
        match t {
            Tok::Punct(b')') => break,
            Tok::Punct(b';') => {}
            Tok::Str(s) => out.push(("doc".to_string(), UsdValue::Str(s))),
            Tok::Ident(mut key) => {
                if matches!(
                    key.as_str(),
                    "prepend" | "append" | "delete" | "add" | "reorder"
                ) {
                    match lx.expect_next("a metadata name")? {
                        (Tok::Ident(k), _) => key = k,
                        (other, l) => {
                            return Err(err(
                                l,
                                format!("expected a metadata name, found {}", show(&other)),
                            ))
                        }
                    }
                }
                if matches!(key.as_str(), "dictionary" | "variants" | "variantSets") {
                    return Err(err(
                        line,
                        format!("metadata '{key}' is not supported by this USDA reader"),
                    ));
                }
                lx.expect_punct(b'=')?;
                out.push((key, parse_value(lx)?));
            }
            other => {
                return Err(err(
                    line,
                    format!("expected metadata, found {}", show(&other)),
                ))
            }
        }
    }
    Ok(out)
}

fn parse_prim(
    lx: &mut Lexer,
    specifier: String,
    parent: &str,
    line: usize,
) -> Result<UsdPrim, UsdaError> {
    let (mut t, mut l) = lx.expect_next("a prim name")?;
    let mut type_name = String::new();
    if let Tok::Ident(ty) = t {
        type_name = ty;
        (t, l) = lx.expect_next("a prim name")?;
    }
    let name = match t {
        Tok::Str(s) => s,
        other => {
            return Err(err(
                l,
                format!("expected a quoted prim name, found {}", show(&other)),
            ))
        }
    };
    if lx.is_punct(b'(')? {
        parse_meta(lx)?;
    }
    lx.expect_punct(b'{')?;
    lx.enter(line)?;
    let path = format!("{parent}/{name}");
    let mut prim = UsdPrim {
        specifier,
        type_name,
        name,
        path: path.clone(),
        attrs: Vec::new(),
        children: Vec::new(),
        line,
    };
    loop {
        let (t, line) = lx.expect_next("a property, a prim or '}'")?;
        let word = match t {
            Tok::Punct(b'}') => break,
            Tok::Punct(b';') => continue,
            Tok::Ident(w) => w,
            other => {
                return Err(err(
                    line,
                    format!("expected a property or a prim, found {}", show(&other)),
                ))
            }
        };
        match word.as_str() {
            "def" | "over" | "class" => {
                let child = parse_prim(lx, word, &path, line)?;
                prim.children.push(child);
            }
            "variantSet" | "variantSets" => {
                return Err(err(
                    line,
                    "variant sets are not supported by this USDA reader",
                ))
            }
            _ => {
                let attr = parse_property(lx, word, line)?;
                prim.attrs.push(attr);
            }
        }
    }
    lx.leave();
    Ok(prim)
}

/// The entries of a typed dictionary after its `{`, as `(name, value)` pairs:
/// `type name = value` items (`dictionary` values nest), separated by newlines or `;`.
fn parse_typed_dict(lx: &mut Lexer) -> Result<UsdValue, UsdaError> {
    let mut items = Vec::new();
    loop {
        if lx.is_punct(b'}')? {
            lx.next()?;
            break;
        }
        if lx.is_punct(b';')? {
            lx.next()?;
            continue;
        }
        let (t, l) = lx.expect_next("a dictionary entry type")?;
        let Tok::Ident(_) = t else {
            return Err(err(
                l,
                format!("expected a dictionary entry type, found {}", show(&t)),
            ));
        };
        if lx.is_punct(b'[')? {
            lx.next()?;
            lx.expect_punct(b']')?;
        }
        let (k, l) = lx.expect_next("a dictionary key")?;
        let key = match k {
            Tok::Ident(s) | Tok::Str(s) => UsdValue::Str(s),
            other => {
                return Err(err(
                    l,
                    format!("expected a dictionary key, found {}", show(&other)),
                ))
            }
        };
        lx.expect_punct(b'=')?;
        items.push((key, parse_value(lx)?));
    }
    lx.leave();
    Ok(UsdValue::Dict(items))
}

fn parse_property(lx: &mut Lexer, first: String, line: usize) -> Result<UsdAttr, UsdaError> {
    let mut word = first;
    while matches!(word.as_str(), "uniform" | "custom" | "varying" | "config") {
        match lx.expect_next("a property type")? {
            (Tok::Ident(w), _) => word = w,
            (other, l) => {
                return Err(err(
                    l,
                    format!("expected a property type, found {}", show(&other)),
                ))
            }
        }
    }
    let mut type_name = word;
    if lx.is_punct(b'[')? {
        lx.next()?;
        lx.expect_punct(b']')?;
        type_name.push_str("[]");
    }
    let name = match lx.expect_next("a property name")? {
        (Tok::Ident(n), _) => n,
        (other, l) => {
            return Err(err(
                l,
                format!(
                    "expected a property name after '{type_name}', found {}",
                    show(&other)
                ),
            ))
        }
    };
    let mut value = None;
    if lx.is_punct(b'=')? {
        lx.next()?;
        value = Some(parse_value(lx)?);
    }
    let mut meta = Vec::new();
    if lx.is_punct(b'(')? {
        meta = parse_meta(lx)?;
    }
    Ok(UsdAttr {
        name,
        type_name,
        value,
        meta,
        line,
    })
}

/// Parses USDA text into prims. Errors carry the line number.
pub fn parse_usda(text: &str) -> Result<UsdLayer, UsdaError> {
    let first = text.lines().next().unwrap_or("");
    if !first.starts_with("#usda ") {
        return Err(err(
            1,
            "not a text USD layer (the first line must be '#usda 1.0'; binary .usdc/.usdz is not supported)",
        ));
    }
    let mut lx = Lexer::new(text);
    let mut layer = UsdLayer::default();
    if lx.is_punct(b'(')? {
        layer.meta = parse_meta(&mut lx)?;
    }
    while let Some((t, line)) = lx.next()? {
        match t {
            Tok::Ident(w) if matches!(w.as_str(), "def" | "over" | "class") => {
                layer.prims.push(parse_prim(&mut lx, w, "", line)?)
            }
            other => {
                return Err(err(
                    line,
                    format!("expected 'def', 'over' or 'class', found {}", show(&other)),
                ))
            }
        }
    }
    Ok(layer)
}
