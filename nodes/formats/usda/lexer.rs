//! USDA tokenizer: numbers, strings (single, double, triple quoted), `<paths>`, identifiers
//! (with `:` and `.` inside, as in `primvars:st` or `points.timeSamples`) and punctuation,
//! each with its 1-based line so every parse error can name the line.

use super::error::UsdaError;

/// One token.
#[derive(Clone, Debug, PartialEq)]
pub(super) enum Tok {
    Punct(u8),
    Str(String),
    Path(String),
    Num(f64),
    Ident(String),
}

/// A one-token-lookahead tokenizer over the layer's bytes.
pub(super) struct Lexer<'a> {
    s: &'a [u8],
    i: usize,
    line: usize,
    peeked: Option<(Tok, usize)>,
    /// How many prims, lists, tuples and dictionaries enclose the parser's position.
    depth: usize,
}

/// The deepest nesting of prims and values the parser follows: real layers nest a few dozen
/// levels, and a limit keeps a hostile file of nested `[` or `def` from overflowing the stack.
pub const MAX_NESTING: usize = 200;

/// An error message prefixed with its line.
pub(super) fn err(line: usize, msg: impl std::fmt::Display) -> UsdaError {
    UsdaError::Line {
        line,
        message: msg.to_string(),
    }
}

impl<'a> Lexer<'a> {
    /// A lexer at the start of `text` (line 1).
    pub(super) fn new(text: &'a str) -> Self {
        Lexer {
            s: text.as_bytes(),
            i: 0,
            line: 1,
            peeked: None,
            depth: 0,
        }
    }

    /// Enters one more level of nesting, opened on `line`; an error past `MAX_NESTING`.
    pub(super) fn enter(&mut self, line: usize) -> Result<(), UsdaError> {
        self.depth += 1;
        if self.depth > MAX_NESTING {
            return Err(err(
                line,
                format!("nesting deeper than {MAX_NESTING} levels of prims or values"),
            ));
        }
        Ok(())
    }

    /// Leaves the level `enter` opened.
    pub(super) fn leave(&mut self) {
        self.depth -= 1;
    }

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

    // One match over the first byte of a token, one arm per token kind: it reads better whole.
    fn lex(&mut self) -> Result<Option<(Tok, usize)>, UsdaError> {
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
            b'@' => {
                // An asset path `@file@`, read as a string (a dome light's texture file).
                let start = self.i + 1;
                let end = self.s[start..]
                    .iter()
                    .position(|&b| b == b'@' || b == b'\n')
                    .map(|p| start + p)
                    .filter(|&e| self.s[e] == b'@')
                    .ok_or_else(|| err(line, "unterminated asset path '@'"))?;
                self.i = end + 1;
                Tok::Str(String::from_utf8_lossy(&self.s[start..end]).into_owned())
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

    pub(super) fn peek(&mut self) -> Result<Option<&(Tok, usize)>, UsdaError> {
        if self.peeked.is_none() {
            self.peeked = self.lex()?;
        }
        Ok(self.peeked.as_ref())
    }

    pub(super) fn next(&mut self) -> Result<Option<(Tok, usize)>, UsdaError> {
        if let Some(t) = self.peeked.take() {
            return Ok(Some(t));
        }
        self.lex()
    }

    pub(super) fn expect_next(&mut self, what: &str) -> Result<(Tok, usize), UsdaError> {
        let line = self.line;
        self.next()?
            .ok_or_else(|| err(line, format!("unexpected end of file, expected {what}")))
    }

    pub(super) fn is_punct(&mut self, c: u8) -> Result<bool, UsdaError> {
        Ok(matches!(self.peek()?, Some((Tok::Punct(p), _)) if *p == c))
    }

    pub(super) fn expect_punct(&mut self, c: u8) -> Result<usize, UsdaError> {
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

/// A token as quoted in error messages.
pub(super) fn show(t: &Tok) -> String {
    match t {
        Tok::Punct(c) => format!("'{}'", *c as char),
        Tok::Str(s) => format!("string \"{s}\""),
        Tok::Path(p) => format!("path <{p}>"),
        Tok::Num(n) => format!("number {n}"),
        Tok::Ident(s) => format!("'{s}'"),
    }
}
