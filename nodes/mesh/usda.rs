//! Text USD (`.usda`) meshes: a parser for the subset Framework3D and Blender write, and a
//! writer Framework3D can open.
//!
//! No USD library exists for Rust, so this reads the layer syntax (prims with `def`/`over`/
//! `class`, typed attributes, relationships, metadata in parentheses, arrays, tuples, paths,
//! `timeSamples` dictionaries) into a small tree, then takes a `Mesh` prim's `points`,
//! `faceVertexCounts`, `faceVertexIndices`, `normals`, `primvars:UVMap` (or `primvars:st`),
//! `primvars:displayColor`, other simple primvars, and the `xformOp`s of the prim and its
//! ancestors (USD row-vector convention: `p_world = p * M_local * M_parent ...`). Anything
//! it does not understand is an error with the line number, never a guess.

use crate::prelude::*;
use std::io::Write;

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

#[derive(Clone, Debug, PartialEq)]
enum Tok {
    Punct(u8),
    Str(String),
    Path(String),
    Num(f64),
    Ident(String),
}

struct Lexer<'a> {
    s: &'a [u8],
    i: usize,
    line: usize,
    peeked: Option<(Tok, usize)>,
}

fn err(line: usize, msg: impl std::fmt::Display) -> String {
    format!("line {line}: {msg}")
}

impl<'a> Lexer<'a> {
    fn skip_ws(&mut self) {
        while self.i < self.s.len() {
            match self.s[self.i] {
                b'\n' => {
                    self.line += 1;
                    self.i += 1;
                }
                b' ' | b'\t' | b'\r' => self.i += 1,
                b'#' => {
                    while self.i < self.s.len() && self.s[self.i] != b'\n' {
                        self.i += 1;
                    }
                }
                _ => break,
            }
        }
    }

    fn lex(&mut self) -> Result<Option<(Tok, usize)>, String> {
        self.skip_ws();
        if self.i >= self.s.len() {
            return Ok(None);
        }
        let line = self.line;
        let c = self.s[self.i];
        let tok = match c {
            b'(' | b')' | b'[' | b']' | b'{' | b'}' | b'=' | b',' | b':' | b';' => {
                self.i += 1;
                Tok::Punct(c)
            }
            b'"' | b'\'' => {
                let triple = self.s[self.i..].starts_with(&[c, c, c]);
                let q = if triple { 3 } else { 1 };
                self.i += q;
                let start = self.i;
                loop {
                    if self.i >= self.s.len() {
                        return Err(err(line, "unterminated string"));
                    }
                    let b = self.s[self.i];
                    if b == b'\\' {
                        self.i += 2;
                        continue;
                    }
                    if b == b'\n' {
                        if !triple {
                            return Err(err(line, "unterminated string"));
                        }
                        self.line += 1;
                    }
                    if b == c && (!triple || self.s[self.i..].starts_with(&[c, c, c])) {
                        break;
                    }
                    self.i += 1;
                }
                let text = String::from_utf8_lossy(&self.s[start..self.i]).into_owned();
                self.i += q;
                Tok::Str(text)
            }
            b'<' => {
                let start = self.i + 1;
                while self.i < self.s.len() && self.s[self.i] != b'>' {
                    if self.s[self.i] == b'\n' {
                        return Err(err(line, "unterminated path '<'"));
                    }
                    self.i += 1;
                }
                if self.i >= self.s.len() {
                    return Err(err(line, "unterminated path '<'"));
                }
                let text = String::from_utf8_lossy(&self.s[start..self.i]).into_owned();
                self.i += 1;
                Tok::Path(text)
            }
            b'0'..=b'9' | b'-' | b'+' | b'.' => {
                let start = self.i;
                self.i += 1;
                while self.i < self.s.len()
                    && matches!(
                        self.s[self.i],
                        b'0'..=b'9' | b'.' | b'e' | b'E' | b'-' | b'+'
                    )
                {
                    self.i += 1;
                }
                let text = std::str::from_utf8(&self.s[start..self.i]).unwrap_or("");
                // `-inf`, `-nan` and the like run into letters: refuse them.
                if self.i < self.s.len() && self.s[self.i].is_ascii_alphabetic() {
                    let end = self.s[self.i..]
                        .iter()
                        .position(|b| !b.is_ascii_alphanumeric())
                        .map_or(self.s.len(), |p| self.i + p);
                    return Err(err(
                        line,
                        format!(
                            "'{}' is not a finite number",
                            String::from_utf8_lossy(&self.s[start..end])
                        ),
                    ));
                }
                let v: f64 = text
                    .parse()
                    .map_err(|_| err(line, format!("malformed number '{text}'")))?;
                Tok::Num(v)
            }
            c if c.is_ascii_alphabetic() || c == b'_' => {
                let start = self.i;
                while self.i < self.s.len()
                    && (self.s[self.i].is_ascii_alphanumeric()
                        || matches!(self.s[self.i], b'_' | b':' | b'.'))
                {
                    self.i += 1;
                }
                // A trailing ':' belongs to a dictionary key, not the name.
                let mut end = self.i;
                if self.s[end - 1] == b':' {
                    end -= 1;
                    self.i = end;
                }
                Tok::Ident(String::from_utf8_lossy(&self.s[start..end]).into_owned())
            }
            other => {
                return Err(err(
                    line,
                    format!("unexpected character '{}'", other as char),
                ))
            }
        };
        Ok(Some((tok, line)))
    }

    fn peek(&mut self) -> Result<Option<&(Tok, usize)>, String> {
        if self.peeked.is_none() {
            self.peeked = self.lex()?;
        }
        Ok(self.peeked.as_ref())
    }

    fn next(&mut self) -> Result<Option<(Tok, usize)>, String> {
        if let Some(t) = self.peeked.take() {
            return Ok(Some(t));
        }
        self.lex()
    }

    fn expect_next(&mut self, what: &str) -> Result<(Tok, usize), String> {
        let line = self.line;
        self.next()?
            .ok_or_else(|| err(line, format!("unexpected end of file, expected {what}")))
    }

    fn is_punct(&mut self, c: u8) -> Result<bool, String> {
        Ok(matches!(self.peek()?, Some((Tok::Punct(p), _)) if *p == c))
    }

    fn expect_punct(&mut self, c: u8) -> Result<usize, String> {
        let (t, line) = self.expect_next(&format!("'{}'", c as char))?;
        if t != Tok::Punct(c) {
            return Err(err(
                line,
                format!("expected '{}', found {}", c as char, show(&t)),
            ));
        }
        Ok(line)
    }
}

fn show(t: &Tok) -> String {
    match t {
        Tok::Punct(c) => format!("'{}'", *c as char),
        Tok::Str(s) => format!("string \"{s}\""),
        Tok::Path(p) => format!("path <{p}>"),
        Tok::Num(n) => format!("number {n}"),
        Tok::Ident(s) => format!("'{s}'"),
    }
}

fn parse_value(lx: &mut Lexer) -> Result<UsdValue, String> {
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
            if open == b'[' {
                UsdValue::List(items)
            } else {
                UsdValue::Tuple(items)
            }
        }
        Tok::Punct(b'{') => {
            let mut items = Vec::new();
            loop {
                if lx.is_punct(b'}')? {
                    lx.next()?;
                    break;
                }
                let (k, l) = lx.expect_next("a time sample key")?;
                let key = match k {
                    Tok::Num(v) => UsdValue::Num(v),
                    Tok::Str(s) => UsdValue::Str(s),
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
fn parse_meta(lx: &mut Lexer) -> Result<Vec<(String, UsdValue)>, String> {
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
) -> Result<UsdPrim, String> {
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
    Ok(prim)
}

fn parse_property(lx: &mut Lexer, first: String, line: usize) -> Result<UsdAttr, String> {
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
pub fn parse_usda(text: &str) -> Result<UsdLayer, String> {
    let first = text.lines().next().unwrap_or("");
    if !first.starts_with("#usda ") {
        return Err(err(
            1,
            "not a text USD layer (the first line must be '#usda 1.0'; binary .usdc/.usdz is not supported)",
        ));
    }
    let mut lx = Lexer {
        s: text.as_bytes(),
        i: 0,
        line: 1,
        peeked: None,
    };
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

fn num(v: &UsdValue, line: usize) -> Result<f64, String> {
    match v {
        UsdValue::Num(x) => Ok(*x),
        other => Err(err(line, format!("expected a number, found {other:?}"))),
    }
}

fn list(a: &UsdAttr) -> Result<&[UsdValue], String> {
    match &a.value {
        Some(UsdValue::List(v)) => Ok(v),
        Some(UsdValue::Dict(_)) => Err(err(
            a.line,
            format!(
                "'{}' is animated (timeSamples); only static meshes are supported",
                a.name
            ),
        )),
        Some(other) => Err(err(
            a.line,
            format!("'{}' should be an array, found {other:?}", a.name),
        )),
        None => Err(err(a.line, format!("'{}' has no value", a.name))),
    }
}

fn check_time_samples(a: &UsdAttr) -> Result<(), String> {
    if a.name.ends_with(".timeSamples") {
        return Err(err(
            a.line,
            format!("'{}' is animated; only static meshes are supported", a.name),
        ));
    }
    Ok(())
}

fn ints(a: &UsdAttr) -> Result<Vec<i64>, String> {
    list(a)?
        .iter()
        .map(|v| {
            let x = num(v, a.line)?;
            if x.fract() != 0.0 {
                return Err(err(a.line, format!("'{}' holds non-integer {x}", a.name)));
            }
            Ok(x as i64)
        })
        .collect()
}

fn tuple_n<const N: usize>(v: &UsdValue, line: usize, name: &str) -> Result<[f64; N], String> {
    match v {
        UsdValue::Tuple(t) if t.len() == N => {
            let mut out = [0.0; N];
            for (o, x) in out.iter_mut().zip(t) {
                *o = num(x, line)?;
            }
            Ok(out)
        }
        other => Err(err(
            line,
            format!("'{name}' expects {N}-tuples, found {other:?}"),
        )),
    }
}

fn tuples<const N: usize>(a: &UsdAttr) -> Result<Vec<[f64; N]>, String> {
    list(a)?
        .iter()
        .map(|v| tuple_n::<N>(v, a.line, &a.name))
        .collect()
}

fn floats(a: &UsdAttr) -> Result<Vec<f64>, String> {
    list(a)?.iter().map(|v| num(v, a.line)).collect()
}

fn matrix(v: &UsdValue, line: usize, name: &str) -> Result<[[f64; 4]; 4], String> {
    match v {
        UsdValue::Tuple(rows) if rows.len() == 4 => {
            let mut m = [[0.0; 4]; 4];
            for (r, row) in rows.iter().enumerate() {
                m[r] = tuple_n::<4>(row, line, name)?;
            }
            Ok(m)
        }
        other => Err(err(
            line,
            format!("'{name}' expects a 4x4 matrix, found {other:?}"),
        )),
    }
}

fn matmul(a: &[[f64; 4]; 4], b: &[[f64; 4]; 4]) -> [[f64; 4]; 4] {
    let mut c = [[0.0; 4]; 4];
    for i in 0..4 {
        for j in 0..4 {
            c[i][j] = (0..4).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    c
}

const IDENTITY: [[f64; 4]; 4] = [
    [1.0, 0.0, 0.0, 0.0],
    [0.0, 1.0, 0.0, 0.0],
    [0.0, 0.0, 1.0, 0.0],
    [0.0, 0.0, 0.0, 1.0],
];

/// Row-vector rotation about axis `k` by `deg` degrees (USD `xformOp:rotateX/Y/Z`).
fn rotation(k: usize, deg: f64) -> [[f64; 4]; 4] {
    let (s, c) = deg.to_radians().sin_cos();
    let (i, j) = ((k + 1) % 3, (k + 2) % 3);
    let mut m = IDENTITY;
    // p' = p * M: the column-vector rotation transposed.
    m[i][i] = c;
    m[i][j] = s;
    m[j][i] = -s;
    m[j][j] = c;
    m
}

/// The local transform of a prim from its `xformOpOrder` (row vectors: the first op in the
/// order applies last, `M = op_n * ... * op_1`).
fn local_transform(p: &UsdPrim) -> Result<[[f64; 4]; 4], String> {
    let Some(order) = p.attr("xformOpOrder") else {
        if let Some(a) = p.attrs.iter().find(|a| a.name.starts_with("xformOp:")) {
            return Err(err(
                a.line,
                format!("'{}' is set but '{}' has no xformOpOrder", a.name, p.path),
            ));
        }
        return Ok(IDENTITY);
    };
    let mut m = IDENTITY;
    for op in list(order)? {
        let (UsdValue::Str(name) | UsdValue::Ident(name)) = op else {
            return Err(err(order.line, "xformOpOrder expects op names"));
        };
        let a = p.attr(name).ok_or_else(|| {
            err(
                order.line,
                format!("xformOpOrder names '{name}' but the prim has no such attribute"),
            )
        })?;
        let v = a
            .value
            .as_ref()
            .ok_or_else(|| err(a.line, format!("'{name}' has no value")))?;
        if matches!(v, UsdValue::Dict(_)) {
            return Err(err(
                a.line,
                format!("'{name}' is animated; only static transforms are supported"),
            ));
        }
        let kind = name.strip_prefix("xformOp:").unwrap_or("");
        let kind = kind.split(':').next().unwrap_or("");
        let op_m = match kind {
            "transform" => matrix(v, a.line, name)?,
            "translate" => {
                let t = tuple_n::<3>(v, a.line, name)?;
                let mut m = IDENTITY;
                m[3][..3].copy_from_slice(&t);
                m
            }
            "scale" => {
                let s = tuple_n::<3>(v, a.line, name)?;
                let mut m = IDENTITY;
                for k in 0..3 {
                    m[k][k] = s[k];
                }
                m
            }
            "rotateX" | "rotateY" | "rotateZ" => {
                let k = (kind.as_bytes()[6] - b'X') as usize;
                rotation(k, num(v, a.line)?)
            }
            "rotateXYZ" => {
                // Rotate about X first, then Y, then Z.
                let r = tuple_n::<3>(v, a.line, name)?;
                matmul(&matmul(&rotation(0, r[0]), &rotation(1, r[1])), &rotation(2, r[2]))
            }
            _ => {
                return Err(err(
                    a.line,
                    format!("transform op '{name}' is not supported (transform, translate, scale, rotateX/Y/Z, rotateXYZ are)"),
                ))
            }
        };
        m = matmul(&op_m, &m);
    }
    Ok(m)
}

/// Finds the prim at `path` (or the first `Mesh`, depth first, when `path` is empty) and
/// the chain of its ancestors, root first.
fn find_mesh<'a>(layer: &'a UsdLayer, path: &str) -> Result<Vec<&'a UsdPrim>, String> {
    fn walk<'a>(
        p: &'a UsdPrim,
        chain: &mut Vec<&'a UsdPrim>,
        want: &dyn Fn(&UsdPrim) -> bool,
    ) -> bool {
        chain.push(p);
        if want(p) {
            return true;
        }
        for c in &p.children {
            if walk(c, chain, want) {
                return true;
            }
        }
        chain.pop();
        false
    }
    let norm = if path.is_empty() || path.starts_with('/') {
        path.to_string()
    } else {
        format!("/{path}")
    };
    let want: Box<dyn Fn(&UsdPrim) -> bool> = if norm.is_empty() {
        Box::new(|p: &UsdPrim| p.type_name == "Mesh" && p.specifier != "class")
    } else {
        Box::new(move |p: &UsdPrim| p.path == norm)
    };
    let mut chain = Vec::new();
    for p in &layer.prims {
        if walk(p, &mut chain, &*want) {
            let last = chain[chain.len() - 1];
            if last.type_name != "Mesh" {
                return Err(format!(
                    "prim '{}' (line {}) is a '{}', not a Mesh; meshes in the file: {}",
                    last.path,
                    last.line,
                    last.type_name,
                    mesh_paths(layer).join(", ")
                ));
            }
            return Ok(chain);
        }
    }
    if path.is_empty() {
        Err("the file has no Mesh prim".into())
    } else {
        Err(format!(
            "no prim at '{path}'; meshes in the file: {}",
            mesh_paths(layer).join(", ")
        ))
    }
}

/// Paths of every `Mesh` prim in the layer.
pub fn mesh_paths(layer: &UsdLayer) -> Vec<String> {
    fn walk(p: &UsdPrim, out: &mut Vec<String>) {
        if p.type_name == "Mesh" {
            out.push(p.path.clone());
        }
        for c in &p.children {
            walk(c, out);
        }
    }
    let mut out = Vec::new();
    for p in &layer.prims {
        walk(p, &mut out);
    }
    out
}

fn interpolation(a: &UsdAttr) -> Result<Option<Domain>, String> {
    let i = a.meta.iter().find(|(k, _)| k == "interpolation");
    Ok(match i.map(|(_, v)| v) {
        None => None,
        Some(UsdValue::Str(s) | UsdValue::Ident(s)) => match s.as_str() {
            "vertex" | "varying" => Some(Domain::Vertex),
            "faceVarying" => Some(Domain::Corner),
            "uniform" => Some(Domain::Face),
            "constant" => None,
            other => return Err(err(a.line, format!("unknown interpolation '{other}'"))),
        },
        Some(other) => return Err(err(a.line, format!("bad interpolation {other:?}"))),
    })
}

fn element_size(a: &UsdAttr) -> Result<usize, String> {
    match a.meta.iter().find(|(k, _)| k == "elementSize") {
        None => Ok(1),
        Some((_, UsdValue::Num(n))) if *n >= 1.0 && n.fract() == 0.0 => Ok(*n as usize),
        Some((_, v)) => Err(err(a.line, format!("bad elementSize {v:?}"))),
    }
}

/// Picks the domain whose size matches an attribute's length, preferring its declared
/// interpolation; `constant` (one value) is broadcast to every vertex.
fn domain_for<T: Clone>(
    a: &UsdAttr,
    values: Vec<T>,
    declared: Option<Domain>,
    counts: (usize, usize, usize),
) -> Result<Attribute<T>, String> {
    let (nv, nc, nf) = counts;
    let size = |d: Domain| match d {
        Domain::Vertex => nv,
        Domain::Corner => nc,
        Domain::Face => nf,
    };
    let constant = a.meta.iter().any(|(k, v)| {
        k == "interpolation"
            && matches!(v, UsdValue::Str(s) | UsdValue::Ident(s) if s == "constant")
    });
    if constant {
        if values.len() != 1 {
            return Err(err(
                a.line,
                format!("'{}' is constant but has {} values", a.name, values.len()),
            ));
        }
        return Ok(Attribute {
            domain: Domain::Vertex,
            values: vec![values[0].clone(); nv],
        });
    }
    // USD's default interpolation for primvars is constant; for `normals` it is vertex.
    let d = declared.unwrap_or(Domain::Vertex);
    if values.len() != size(d) {
        return Err(err(
            a.line,
            format!(
                "'{}' has {} values but its {:?} interpolation needs {}",
                a.name,
                values.len(),
                d,
                size(d)
            ),
        ));
    }
    Ok(Attribute { domain: d, values })
}

/// Expands an indexed primvar (`primvars:st:indices`).
fn expand_indexed<T: Clone>(prim: &UsdPrim, a: &UsdAttr, values: Vec<T>) -> Result<Vec<T>, String> {
    let Some(ix) = prim.attr(&format!("{}:indices", a.name)) else {
        return Ok(values);
    };
    ints(ix)?
        .into_iter()
        .map(|i| {
            values
                .get(i as usize)
                .cloned()
                .filter(|_| i >= 0)
                .ok_or_else(|| {
                    err(
                        ix.line,
                        format!(
                            "index {i} out of range for '{}' ({} values)",
                            a.name,
                            values.len()
                        ),
                    )
                })
        })
        .collect()
}

/// Reads the mesh at `prim_path` (the first Mesh when empty) from USDA text, with the
/// transforms of the prim and its ancestors applied when `apply_transform` is set.
pub fn read_usda(text: &str, prim_path: &str, apply_transform: bool) -> Result<Mesh, String> {
    let layer = parse_usda(text)?;
    let chain = find_mesh(&layer, prim_path)?;
    let prim = chain[chain.len() - 1];
    for a in &prim.attrs {
        check_time_samples(a).or_else(|e| {
            // Animation on attributes the mesh does not read is harmless.
            let base = a.name.trim_end_matches(".timeSamples");
            if ["points", "faceVertexCounts", "faceVertexIndices", "normals"].contains(&base)
                || base.starts_with("primvars:")
                || base.starts_with("xformOp:")
            {
                Err(e)
            } else {
                Ok(())
            }
        })?;
    }
    let need = |n: &str| {
        prim.attr(n)
            .ok_or_else(|| format!("Mesh '{}' (line {}) has no '{n}'", prim.path, prim.line))
    };
    let pa = need("points")?;
    let mut positions = tuples::<3>(pa)?;
    let ca = need("faceVertexCounts")?;
    let ia = need("faceVertexIndices")?;
    let counts = ints(ca)?;
    let idx = ints(ia)?;
    let nv = positions.len();
    let mut c32 = Vec::with_capacity(counts.len());
    for (f, &c) in counts.iter().enumerate() {
        if c < 3 {
            return Err(err(
                ca.line,
                format!("face {f} has {c} corners; a face needs at least 3"),
            ));
        }
        c32.push(c as u32);
    }
    let mut i32v = Vec::with_capacity(idx.len());
    for (k, &i) in idx.iter().enumerate() {
        if i < 0 || i as usize >= nv {
            return Err(err(
                ia.line,
                format!("faceVertexIndices[{k}] = {i} is out of range ({nv} points)"),
            ));
        }
        i32v.push(i as u32);
    }
    let sum: i64 = counts.iter().sum();
    if sum as usize != idx.len() {
        return Err(err(
            ia.line,
            format!(
                "faceVertexCounts add up to {sum} but faceVertexIndices has {} entries",
                idx.len()
            ),
        ));
    }
    let nc = i32v.len();
    let nf = c32.len();
    let sizes = (nv, nc, nf);
    let mut normals = None;
    let na = prim.attr("primvars:normals").or(prim.attr("normals"));
    if let Some(a) = na {
        let v = expand_indexed(prim, a, tuples::<3>(a)?)?;
        normals = Some(domain_for(a, v, interpolation(a)?, sizes)?);
    }
    let mut uvs = None;
    let ua = prim
        .attr("primvars:UVMap")
        .or(prim.attr("primvars:st"))
        .or(prim.attr("primvars:uv"));
    if let Some(a) = ua {
        let v = expand_indexed(prim, a, tuples::<2>(a)?)?;
        uvs = Some(domain_for(a, v, interpolation(a)?, sizes)?);
    }
    let mut colors = None;
    if let Some(a) = prim.attr("primvars:displayColor") {
        let v = expand_indexed(prim, a, tuples::<3>(a)?)?;
        colors = Some(domain_for(a, v, interpolation(a)?, sizes)?);
    }
    let mut attributes = std::collections::BTreeMap::new();
    for a in &prim.attrs {
        let Some(name) = a.name.strip_prefix("primvars:") else {
            continue;
        };
        if name.ends_with(":indices")
            || ua.is_some_and(|u| std::ptr::eq(u, a))
            || na.is_some_and(|u| std::ptr::eq(u, a))
            || name == "displayColor"
            || a.value.is_none()
        {
            continue;
        }
        if element_size(a)? != 1 {
            continue; // e.g. skinning weights with several influences: not a per-element value
        }
        let d = interpolation(a)?;
        let ty = a.type_name.trim_start_matches("uniform ");
        let data = match ty {
            "float[]" | "double[]" | "half[]" => AttributeData::Float(domain_for(
                a,
                expand_indexed(prim, a, floats(a)?)?,
                d,
                sizes,
            )?),
            "int[]" | "bool[]" => {
                AttributeData::Int(domain_for(a, expand_indexed(prim, a, ints(a)?)?, d, sizes)?)
            }
            "float2[]" | "double2[]" | "texCoord2f[]" | "texCoord2d[]" => AttributeData::Vec2(
                domain_for(a, expand_indexed(prim, a, tuples::<2>(a)?)?, d, sizes)?,
            ),
            "float3[]" | "double3[]" | "color3f[]" | "normal3f[]" | "vector3f[]" | "point3f[]" => {
                AttributeData::Vec3(domain_for(
                    a,
                    expand_indexed(prim, a, tuples::<3>(a)?)?,
                    d,
                    sizes,
                )?)
            }
            _ => continue, // other primvars (matrices, tokens) carry no per-element data
        };
        attributes.insert(name.to_string(), data);
    }
    // Left-handed meshes wind clockwise: reverse faces so outputs are counter-clockwise.
    let left = prim
        .attr("orientation")
        .and_then(|a| a.value.as_ref())
        .is_some_and(|v| matches!(v, UsdValue::Str(s) | UsdValue::Ident(s) if s == "leftHanded"));
    if apply_transform {
        let mut m = IDENTITY;
        for p in &chain {
            // world = local(mesh) * local(parent) * ... : prepend each deeper prim.
            m = matmul(&local_transform(p)?, &m);
        }
        if m != IDENTITY {
            for p in positions.iter_mut() {
                let v = [p[0], p[1], p[2], 1.0];
                let mut o = [0.0; 4];
                for j in 0..4 {
                    o[j] = (0..4).map(|k| v[k] * m[k][j]).sum();
                }
                let wh = o[3];
                if wh != 1.0 && wh != 0.0 {
                    for x in o.iter_mut().take(3) {
                        *x /= wh;
                    }
                }
                *p = [o[0], o[1], o[2]];
            }
            if let Some(n) = normals.as_mut() {
                let a = nalgebra::Matrix3::from_fn(|i, j| m[i][j]);
                let inv_t = a
                    .try_inverse()
                    .ok_or_else(|| format!("the transform of '{}' is singular", prim.path))?
                    .transpose();
                for v in n.values.iter_mut() {
                    // row vector n' = n * (A^-1)^T
                    let r = nalgebra::RowVector3::new(v[0], v[1], v[2]) * inv_t;
                    let len = r.norm();
                    *v = if len > 0.0 {
                        [r[0] / len, r[1] / len, r[2] / len]
                    } else {
                        [r[0], r[1], r[2]]
                    };
                }
            }
        }
    }
    let mut mesh = Mesh::new(positions, c32, i32v).map_err(|e| match e {
        MeshError::NonFinite { .. } => err(pa.line, e),
        _ => err(ia.line, e),
    })?;
    mesh.normals = normals;
    mesh.uvs = uvs;
    mesh.colors = colors;
    mesh.attributes = attributes;
    if left {
        reverse_faces(&mut mesh);
    }
    mesh.check().map_err(|e| e.to_string())?;
    Ok(mesh)
}

/// Reverses the winding of every face, carrying per-corner data along.
pub fn reverse_faces(mesh: &mut Mesh) {
    let starts = mesh.face_starts().to_vec();
    let nc = mesh.face_indices().len();
    let mut perm: Vec<usize> = (0..nc).collect();
    for f in 0..mesh.num_faces() {
        perm[starts[f] as usize..starts[f + 1] as usize].reverse();
    }
    let idx: Vec<u32> = perm.iter().map(|&c| mesh.face_indices()[c]).collect();
    let counts = mesh.face_counts().to_vec();
    fn re<T: Clone>(a: &mut Option<Attribute<T>>, perm: &[usize]) {
        if let Some(a) = a.as_mut().filter(|a| a.domain == Domain::Corner) {
            a.values = perm.iter().map(|&c| a.values[c].clone()).collect();
        }
    }
    let mut uvs = mesh.uvs.take();
    let mut normals = mesh.normals.take();
    let mut colors = mesh.colors.take();
    re(&mut uvs, &perm);
    re(&mut normals, &perm);
    re(&mut colors, &perm);
    let mut attrs = std::mem::take(&mut mesh.attributes);
    for a in attrs.values_mut() {
        macro_rules! fix {
            ($x:expr) => {
                if $x.domain == Domain::Corner {
                    $x.values = perm.iter().map(|&c| $x.values[c].clone()).collect();
                }
            };
        }
        match a {
            AttributeData::Float(x) => fix!(x),
            AttributeData::Vec2(x) => fix!(x),
            AttributeData::Vec3(x) => fix!(x),
            AttributeData::Int(x) => fix!(x),
        }
    }
    mesh.set_faces(counts, idx);
    mesh.uvs = uvs;
    mesh.normals = normals;
    mesh.colors = colors;
    mesh.attributes = attrs;
}

fn interp_name(d: Domain) -> &'static str {
    match d {
        Domain::Vertex => "vertex",
        Domain::Corner => "faceVarying",
        Domain::Face => "uniform",
    }
}

fn write_tuples<const N: usize>(w: &mut dyn Write, v: &[[f64; N]]) -> std::io::Result<()> {
    write!(w, "[")?;
    for (i, t) in v.iter().enumerate() {
        if i > 0 {
            write!(w, ", ")?;
        }
        write!(w, "(")?;
        for (k, x) in t.iter().enumerate() {
            if k > 0 {
                write!(w, ", ")?;
            }
            write!(w, "{x}")?;
        }
        write!(w, ")")?;
    }
    write!(w, "]")
}

fn write_list<T: std::fmt::Display>(w: &mut dyn Write, v: &[T]) -> std::io::Result<()> {
    write!(w, "[")?;
    for (i, x) in v.iter().enumerate() {
        if i > 0 {
            write!(w, ", ")?;
        }
        write!(w, "{x}")?;
    }
    write!(w, "]")
}

/// A valid USD identifier made from `s` (letters, digits, `_`; not starting with a digit).
pub fn usd_identifier(s: &str) -> String {
    let mut out: String = s
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    if out.is_empty() || out.as_bytes()[0].is_ascii_digit() {
        out.insert(0, '_');
    }
    out
}

/// Writes `mesh` as a USDA layer Framework3D (and `usdview`) can open: an `Xform` per path
/// element of `prim_path` around a `Mesh`, with points, faces, normals, `primvars:UVMap`,
/// `primvars:displayColor` and the named attributes as primvars. Floats are written with
/// Rust's shortest round-trip formatting, so reading the file back gives the same values.
pub fn write_usda(mesh: &Mesh, prim_path: &str, w: &mut dyn Write) -> std::io::Result<()> {
    let parts: Vec<String> = prim_path
        .split('/')
        .filter(|s| !s.is_empty())
        .map(usd_identifier)
        .collect();
    let parts = if parts.is_empty() {
        vec!["mesh".to_string(), "mesh".to_string()]
    } else {
        parts
    };
    writeln!(w, "#usda 1.0")?;
    writeln!(w, "(")?;
    writeln!(w, "    defaultPrim = \"{}\"", parts[0])?;
    writeln!(w, "    doc = \"written by cgnodes\"")?;
    writeln!(w, "    metersPerUnit = 1")?;
    writeln!(w, "    upAxis = \"Z\"")?;
    writeln!(w, ")")?;
    writeln!(w)?;
    let n = parts.len();
    for (d, p) in parts.iter().enumerate() {
        let ind = "    ".repeat(d);
        let ty = if d + 1 == n { "Mesh" } else { "Xform" };
        writeln!(w, "{ind}def {ty} \"{p}\"")?;
        writeln!(w, "{ind}{{")?;
    }
    let ind = "    ".repeat(n);
    let (lo, hi) = mesh.bounds();
    write!(w, "{ind}float3[] extent = ")?;
    write_tuples(w, &[lo, hi])?;
    writeln!(w)?;
    write!(w, "{ind}int[] faceVertexCounts = ")?;
    write_list(w, mesh.face_counts())?;
    writeln!(w)?;
    write!(w, "{ind}int[] faceVertexIndices = ")?;
    write_list(w, mesh.face_indices())?;
    writeln!(w)?;
    if let Some(nm) = &mesh.normals {
        write!(w, "{ind}normal3f[] normals = ")?;
        write_tuples(w, &nm.values)?;
        writeln!(
            w,
            " (\n{ind}    interpolation = \"{}\"\n{ind})",
            interp_name(nm.domain)
        )?;
    }
    write!(w, "{ind}point3f[] points = ")?;
    write_tuples(w, &mesh.positions)?;
    writeln!(w)?;
    if let Some(c) = &mesh.colors {
        write!(w, "{ind}color3f[] primvars:displayColor = ")?;
        write_tuples(w, &c.values)?;
        writeln!(
            w,
            " (\n{ind}    interpolation = \"{}\"\n{ind})",
            interp_name(c.domain)
        )?;
    }
    if let Some(uv) = &mesh.uvs {
        write!(w, "{ind}texCoord2f[] primvars:UVMap = ")?;
        write_tuples(w, &uv.values)?;
        writeln!(
            w,
            " (\n{ind}    interpolation = \"{}\"\n{ind})",
            interp_name(uv.domain)
        )?;
    }
    for (name, a) in &mesh.attributes {
        let name = usd_identifier(name);
        let d = match a {
            AttributeData::Float(x) => {
                write!(w, "{ind}double[] primvars:{name} = ")?;
                write_list(w, &x.values)?;
                x.domain
            }
            AttributeData::Int(x) => {
                write!(w, "{ind}int[] primvars:{name} = ")?;
                write_list(w, &x.values)?;
                x.domain
            }
            AttributeData::Vec2(x) => {
                write!(w, "{ind}double2[] primvars:{name} = ")?;
                write_tuples(w, &x.values)?;
                x.domain
            }
            AttributeData::Vec3(x) => {
                write!(w, "{ind}double3[] primvars:{name} = ")?;
                write_tuples(w, &x.values)?;
                x.domain
            }
        };
        writeln!(
            w,
            " (\n{ind}    interpolation = \"{}\"\n{ind})",
            interp_name(d)
        )?;
    }
    writeln!(w, "{ind}uniform token subdivisionScheme = \"none\"")?;
    for d in (0..n).rev() {
        writeln!(w, "{}}}", "    ".repeat(d))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const QUAD: &str = r#"#usda 1.0
(
    defaultPrim = "Root"
)

def Xform "Root"
{
    double3 xformOp:translate = (1, 2, 3)
    uniform token[] xformOpOrder = ["xformOp:translate"]

    def Mesh "Quad" (
        prepend apiSchemas = ["MaterialBindingAPI"]
    )
    {
        int[] faceVertexCounts = [4]
        int[] faceVertexIndices = [0, 1, 2, 3]
        point3f[] points = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)]
        texCoord2f[] primvars:st = [(0, 0), (1, 1)] (
            interpolation = "faceVarying"
        )
        int[] primvars:st:indices = [0, 1, 1, 0]
        rel material:binding = </mat>
    }
}
"#;

    #[test]
    fn reads_translated_quad_with_indexed_uvs() {
        let m = read_usda(QUAD, "", true).unwrap();
        assert_eq!(m.positions[2], [2.0, 3.0, 3.0]);
        assert_eq!(m.face_counts(), &[4]);
        let uv = m.uvs.unwrap();
        assert_eq!(uv.domain, Domain::Corner);
        assert_eq!(
            uv.values,
            vec![[0.0, 0.0], [1.0, 1.0], [1.0, 1.0], [0.0, 0.0]]
        );
        let raw = read_usda(QUAD, "/Root/Quad", false).unwrap();
        assert_eq!(raw.positions[2], [1.0, 1.0, 0.0]);
    }

    #[test]
    fn rotate_x_turns_y_into_z() {
        // USD rotateX by +90 degrees maps +Y to +Z (right-handed).
        let m = rotation(0, 90.0);
        let p = [0.0, 1.0, 0.0, 1.0];
        let z: f64 = (0..4).map(|k| p[k] * m[k][2]).sum();
        assert!((z - 1.0).abs() < 1e-12);
    }

    #[test]
    fn errors_name_the_line() {
        let bad = QUAD.replace("(1, 0, 0), (1, 1, 0)", "(1, 0, 0), (1, 1 0)");
        let e = read_usda(&bad, "", true).unwrap_err();
        assert!(e.starts_with("line 17:"), "{e}");
        let bad = QUAD.replace("[0, 1, 2, 3]", "[0, 1, 2, 7]");
        let e = read_usda(&bad, "", true).unwrap_err();
        assert!(e.contains("line 16") && e.contains("out of range"), "{e}");
        let bad = QUAD.replace("(0, 1, 0)]", "(0, nan, 0)]");
        let e = read_usda(&bad, "", true).unwrap_err();
        assert!(e.contains("line 17") && e.contains("finite"), "{e}");
        let bad = QUAD.replace("def Mesh", "def Mesh Mesh");
        assert!(read_usda(&bad, "", true)
            .unwrap_err()
            .starts_with("line 11:"));
        let e = read_usda(QUAD, "/Root", true).unwrap_err();
        assert!(e.contains("not a Mesh"), "{e}");
        let bad = QUAD.replace("xformOp:translate\"]", "xformOp:shear\"]");
        let e = read_usda(&bad, "", true).unwrap_err();
        assert!(e.contains("line 9"), "{e}");
    }

    #[test]
    fn write_then_read_is_exact() {
        let mut m = read_usda(QUAD, "", true).unwrap();
        m.positions[1][0] = 0.1 + 0.2; // not representable in f32
        let mut buf = Vec::new();
        write_usda(&m, "/a/b", &mut buf).unwrap();
        let text = String::from_utf8(buf).unwrap();
        let r = read_usda(&text, "/a/b", true).unwrap();
        assert_eq!(r.positions, m.positions);
        assert_eq!(r.face_indices(), m.face_indices());
        assert_eq!(r.uvs, m.uvs);
    }
}
