//! Provenance records inside written files, at the byte level: a one-line JSON text (what
//! made the file) embedded where each format keeps free text, and read back. PNG: a `tEXt`
//! chunk with keyword `cgnodes`; OpenEXR: a `string` header attribute `cgnodes`; OBJ and MTL:
//! a `# cgnodes ...` comment line; PLY: a `comment cgnodes ...` header line; USDA: the
//! layer's `customLayerData` entry `cgnodes`; SVG: an XML comment. Other formats (CSV, JPEG,
//! GIF, JSON, ...) get a sidecar `FILE.provenance.json` (`sidecar_path`).

use std::path::{Path, PathBuf};

/// Where the record of a file with this extension goes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Carrier {
    Png,
    Exr,
    /// `# ` comment lines (OBJ, MTL).
    HashComment,
    Ply,
    Usda,
    Svg,
    /// A sidecar `FILE.provenance.json`.
    Sidecar,
}

/// The carrier for `path`, by its extension.
pub fn carrier(path: &Path) -> Carrier {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or_default()
        .to_ascii_lowercase();
    match ext.as_str() {
        "png" => Carrier::Png,
        "exr" => Carrier::Exr,
        "obj" | "mtl" => Carrier::HashComment,
        "ply" => Carrier::Ply,
        "usda" | "usd" => Carrier::Usda,
        "svg" => Carrier::Svg,
        _ => Carrier::Sidecar,
    }
}

/// The sidecar of `path`: `path` with `.provenance.json` appended.
pub fn sidecar_path(path: &Path) -> PathBuf {
    let mut s = path.as_os_str().to_owned();
    s.push(".provenance.json");
    PathBuf::from(s)
}

/// JSON text with every non-ASCII character written as a `\u` escape, so that it fits
/// formats whose text fields are Latin-1 (PNG `tEXt`) or ASCII; same JSON value.
pub fn ascii_json(v: &serde_json::Value) -> String {
    let s = v.to_string();
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        if c.is_ascii() {
            out.push(c);
        } else {
            let mut buf = [0u16; 2];
            for u in c.encode_utf16(&mut buf) {
                out.push_str(&format!("\\u{u:04x}"));
            }
        }
    }
    out
}

/// `bytes` of a file at `path` with the one-line ASCII JSON `record` embedded, or `None` when
/// the format has no place for it (or the bytes are not what the extension says): the
/// caller then writes a sidecar.
pub fn embed(path: &Path, bytes: &[u8], record: &str) -> Option<Vec<u8>> {
    match carrier(path) {
        Carrier::Png => png_embed(bytes, record),
        Carrier::Exr => exr_embed(bytes, record),
        Carrier::HashComment => {
            let mut out = format!("# cgnodes {record}\n").into_bytes();
            out.extend_from_slice(bytes);
            Some(out)
        }
        Carrier::Ply => ply_embed(bytes, record),
        Carrier::Usda => usda_embed(bytes, record),
        Carrier::Svg => svg_embed(bytes, record),
        Carrier::Sidecar => None,
    }
}

/// The embedded record of a file at `path` (the JSON text), `None` when there is none.
pub fn extract(path: &Path, bytes: &[u8]) -> Option<String> {
    match carrier(path) {
        Carrier::Png => png_extract(bytes),
        Carrier::Exr => exr_extract(bytes),
        Carrier::HashComment => text_lines(bytes)
            .take_while(|l| l.starts_with('#'))
            .find_map(|l| l.strip_prefix("# cgnodes ").map(str::to_string)),
        Carrier::Ply => text_lines(bytes)
            .take_while(|l| *l != "end_header")
            .find_map(|l| l.strip_prefix("comment cgnodes ").map(str::to_string)),
        Carrier::Usda => usda_extract(bytes),
        Carrier::Svg => {
            let s = std::str::from_utf8(bytes).ok()?;
            let start = s.find("<!-- cgnodes ")? + "<!-- cgnodes ".len();
            let end = s[start..].find(" -->")? + start;
            Some(s[start..end].replace("-\\u002d", "--"))
        }
        Carrier::Sidecar => None,
    }
}

fn text_lines(bytes: &[u8]) -> impl Iterator<Item = &str> {
    bytes
        .split(|&b| b == b'\n')
        .map(|l| std::str::from_utf8(l).unwrap_or("").trim_end_matches('\r'))
}

/// CRC-32 (ISO 3309, as PNG uses it) of `data`.
fn crc32(data: &[u8]) -> u32 {
    crc32fast::hash(data)
}

const PNG_SIG: &[u8] = b"\x89PNG\r\n\x1a\n";

/// Inserts a `tEXt` chunk (keyword `cgnodes`) right after IHDR (PNG 1.2, section 4.2.3.1).
fn png_embed(bytes: &[u8], record: &str) -> Option<Vec<u8>> {
    if !bytes.starts_with(PNG_SIG) || bytes.get(12..16)? != b"IHDR" {
        return None;
    }
    let ihdr_len = u32::from_be_bytes(bytes.get(8..12)?.try_into().ok()?) as usize;
    let at = 8 + 12 + ihdr_len;
    let mut body = b"tEXtcgnodes\0".to_vec();
    body.extend_from_slice(record.as_bytes());
    let mut out = Vec::with_capacity(bytes.len() + body.len() + 8);
    out.extend_from_slice(bytes.get(..at)?);
    out.extend_from_slice(&((body.len() - 4) as u32).to_be_bytes());
    out.extend_from_slice(&body);
    out.extend_from_slice(&crc32(&body).to_be_bytes());
    out.extend_from_slice(&bytes[at..]);
    Some(out)
}

fn png_extract(bytes: &[u8]) -> Option<String> {
    if !bytes.starts_with(PNG_SIG) {
        return None;
    }
    let mut i = 8;
    while i + 12 <= bytes.len() {
        let len = u32::from_be_bytes(bytes[i..i + 4].try_into().ok()?) as usize;
        let ty = &bytes[i + 4..i + 8];
        let data = bytes.get(i + 8..i + 8 + len)?;
        if ty == b"tEXt" {
            if let Some(text) = data.strip_prefix(b"cgnodes\0") {
                return Some(text.iter().map(|&b| b as char).collect());
            }
        }
        if ty == b"IEND" {
            break;
        }
        i += 12 + len;
    }
    None
}

/// An OpenEXR header attribute: name, type name, and where its value lies in the file.
type ExrAttr = (String, String, std::ops::Range<usize>);

/// The end of a single-part OpenEXR header (the index of its terminating null byte) and the
/// attributes before it as (name, type, value range).
fn exr_header(bytes: &[u8]) -> Option<(usize, Vec<ExrAttr>)> {
    if bytes.get(..4)? != [0x76, 0x2f, 0x31, 0x01] {
        return None;
    }
    let flags = u32::from_le_bytes(bytes.get(4..8)?.try_into().ok()?);
    // Multi-part (0x1000) and deep (0x800) files keep several headers or tables: sidecar.
    if flags & 0x1800 != 0 {
        return None;
    }
    let cstr = |i: usize| -> Option<(String, usize)> {
        let n = bytes.get(i..)?.iter().position(|&b| b == 0)?;
        Some((
            String::from_utf8_lossy(&bytes[i..i + n]).into_owned(),
            i + n + 1,
        ))
    };
    let mut attrs = Vec::new();
    let mut i = 8;
    loop {
        if *bytes.get(i)? == 0 {
            return Some((i, attrs));
        }
        let (name, j) = cstr(i)?;
        let (ty, k) = cstr(j)?;
        let size = i32::from_le_bytes(bytes.get(k..k + 4)?.try_into().ok()?);
        let start = k + 4;
        let end = start.checked_add(usize::try_from(size).ok()?)?;
        if end > bytes.len() {
            return None;
        }
        attrs.push((name, ty, start..end));
        i = end;
    }
}

/// Adds a `string` attribute `cgnodes` at the end of the header and moves the chunk offset
/// table's entries by the bytes inserted. The table's length follows from its first entry,
/// which points just past the table (OpenEXR file layout: header, offset table, chunks).
fn exr_embed(bytes: &[u8], record: &str) -> Option<Vec<u8>> {
    let (end, _) = exr_header(bytes)?;
    let table = end + 1;
    let first = u64::from_le_bytes(bytes.get(table..table + 8)?.try_into().ok()?) as usize;
    let span = first.checked_sub(table)?;
    if span == 0 || span % 8 != 0 || first > bytes.len() {
        return None;
    }
    let mut attr = b"cgnodes\0string\0".to_vec();
    attr.extend_from_slice(&i32::try_from(record.len()).ok()?.to_le_bytes());
    attr.extend_from_slice(record.as_bytes());
    let shift = attr.len() as u64;
    let mut out = Vec::with_capacity(bytes.len() + attr.len());
    out.extend_from_slice(&bytes[..end]);
    out.extend_from_slice(&attr);
    out.push(0);
    for k in 0..span / 8 {
        let at = table + 8 * k;
        let off = u64::from_le_bytes(bytes[at..at + 8].try_into().ok()?);
        out.extend_from_slice(&(off + shift).to_le_bytes());
    }
    out.extend_from_slice(&bytes[first..]);
    Some(out)
}

fn exr_extract(bytes: &[u8]) -> Option<String> {
    let (_, attrs) = exr_header(bytes)?;
    attrs
        .into_iter()
        .find(|(n, t, _)| n == "cgnodes" && t == "string")
        .map(|(_, _, r)| String::from_utf8_lossy(&bytes[r]).into_owned())
}

/// Adds `comment cgnodes ...` after the `format` line of a PLY header.
fn ply_embed(bytes: &[u8], record: &str) -> Option<Vec<u8>> {
    if !bytes.starts_with(b"ply") {
        return None;
    }
    let fmt = find(bytes, b"\nformat ")?;
    let eol = fmt + 1 + bytes[fmt + 1..].iter().position(|&b| b == b'\n')? + 1;
    let mut out = bytes[..eol].to_vec();
    out.extend_from_slice(format!("comment cgnodes {record}\n").as_bytes());
    out.extend_from_slice(&bytes[eol..]);
    Some(out)
}

fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}

/// The record as a USD string literal: quotes and backslashes escaped.
fn usd_quote(record: &str) -> String {
    record.replace('\\', "\\\\").replace('"', "\\\"")
}

/// Adds `customLayerData = { string cgnodes = "..." }` to the layer metadata of a text USD
/// layer (creating the metadata block when the layer has none).
fn usda_embed(bytes: &[u8], record: &str) -> Option<Vec<u8>> {
    let text = std::str::from_utf8(bytes).ok()?;
    let first_eol = text.find('\n')? + 1;
    if !text.starts_with("#usda ") {
        return None;
    }
    let entry = format!(
        "    customLayerData = {{\n        string cgnodes = \"{}\"\n    }}\n",
        usd_quote(record)
    );
    let rest = &text[first_eol..];
    let mut out = text[..first_eol].to_string();
    if let Some(after) = rest.strip_prefix("(\n") {
        out.push_str("(\n");
        out.push_str(&entry);
        out.push_str(after);
    } else {
        out.push_str(&format!("(\n{entry})\n"));
        out.push_str(rest);
    }
    Some(out.into_bytes())
}

fn usda_extract(bytes: &[u8]) -> Option<String> {
    let text = std::str::from_utf8(bytes).ok()?;
    let key = "string cgnodes = \"";
    let start = text.find(key)? + key.len();
    let mut out = String::new();
    let mut chars = text[start..].chars();
    while let Some(c) = chars.next() {
        match c {
            '\\' => out.push(chars.next()?),
            '"' => return Some(out),
            c => out.push(c),
        }
    }
    None
}

/// Adds `<!-- cgnodes ... -->` after the XML declaration (or at the start); `--` cannot
/// appear in an XML comment, so it is written as the equivalent JSON escape `-\u002d`.
fn svg_embed(bytes: &[u8], record: &str) -> Option<Vec<u8>> {
    let text = std::str::from_utf8(bytes).ok()?;
    let comment = format!("<!-- cgnodes {} -->\n", record.replace("--", "-\\u002d"));
    let at = if text.starts_with("<?xml") {
        text.find("?>")? + 2
    } else {
        0
    };
    let mut out = text[..at].to_string();
    if at > 0 {
        out.push('\n');
    }
    out.push_str(&comment);
    out.push_str(text[at..].trim_start_matches('\n'));
    Some(out.into_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crc32_matches_the_standard_check_value() {
        // The check value of CRC-32/ISO-HDLC for "123456789".
        assert_eq!(crc32(b"123456789"), 0xcbf4_3926);
        // PNG's IEND chunk carries the CRC of its type alone.
        assert_eq!(crc32(b"IEND"), 0xae42_6082);
    }

    #[test]
    fn ascii_json_escapes_non_ascii_and_parses_back_the_same() {
        let v = serde_json::json!({"path": "café/日本/😀.png", "x": 1.5});
        let s = ascii_json(&v);
        assert!(s.is_ascii());
        assert_eq!(serde_json::from_str::<serde_json::Value>(&s).unwrap(), v);
    }

    #[test]
    fn text_carriers_round_trip() {
        let rec = r#"{"node":"a--b","p":"q\"r\\s"}"#;
        for (name, body) in [
            ("m.obj", "v 0 0 0\n"),
            (
                "m.ply",
                "ply\nformat ascii 1.0\nelement vertex 0\nend_header\n",
            ),
            ("m.usda", "#usda 1.0\n(\n    upAxis = \"Z\"\n)\n"),
            ("m.usda", "#usda 1.0\ndef Xform \"a\" {\n}\n"),
            ("c.svg", "<?xml version=\"1.0\"?>\n<svg></svg>\n"),
        ] {
            let p = Path::new(name);
            let out = embed(p, body.as_bytes(), rec).expect(name);
            assert_eq!(extract(p, &out).as_deref(), Some(rec), "{name}");
            assert!(extract(p, body.as_bytes()).is_none(), "{name}");
        }
        assert!(embed(Path::new("t.csv"), b"a\n1\n", rec).is_none());
    }
}
