//! CSV through the `csv` crate, so that every CSV cgnodes writes or reads (sweep results,
//! tables, chart inputs, reference series) quotes the same way (RFC 4180: fields with a
//! comma, a quote or a line break are quoted, quotes doubled) and ends lines with `\n`.

/// CSV text of `records`; a header row is just the first record.
pub fn to_text<R, F>(records: impl IntoIterator<Item = R>) -> String
where
    R: IntoIterator<Item = F>,
    F: AsRef<str>,
{
    let mut w = csv::WriterBuilder::new()
        .flexible(true)
        .from_writer(Vec::new());
    for r in records {
        for f in r {
            w.write_field(f.as_ref())
                .expect("writing CSV into memory cannot fail");
        }
        w.write_record(None::<&[u8]>)
            .expect("writing CSV into memory cannot fail");
    }
    let bytes = w
        .into_inner()
        .expect("flushing CSV into memory cannot fail");
    String::from_utf8(bytes).expect("CSV of UTF-8 fields is UTF-8")
}

/// A CSV read whole: its header row and the rows after it (which may have more or fewer
/// fields than the header).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Rows {
    /// The first row.
    pub header: Vec<String>,
    /// The other rows.
    pub rows: Vec<Vec<String>>,
}

impl Rows {
    /// The index of column `name` in the header.
    pub fn column(&self, name: &str) -> Option<usize> {
        self.header.iter().position(|h| h == name)
    }
}

/// Reads CSV text with a header row; `None` when there is no row at all. Blank lines are
/// skipped, and so are lines starting with `#` when `comments` is set; fields (and header
/// names) are trimmed when `trim` is set.
pub fn read(text: &str, comments: bool, trim: bool) -> Result<Option<Rows>, String> {
    let mut r = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .comment(comments.then_some(b'#'))
        .trim(if trim {
            csv::Trim::All
        } else {
            csv::Trim::None
        })
        .from_reader(text.as_bytes());
    let mut all = Vec::new();
    for rec in r.records() {
        let rec = rec.map_err(|e| e.to_string())?;
        // A line of spaces is blank too.
        if rec.len() == 1 && rec[0].trim().is_empty() {
            continue;
        }
        all.push(rec.iter().map(String::from).collect::<Vec<_>>());
    }
    check_complete(text, &all)?;
    let mut it = all.into_iter();
    Ok(it.next().map(|header| Rows {
        header,
        rows: it.collect(),
    }))
}

/// A file cut short is an error, not a shorter table: an unterminated quoted field (an odd
/// number of quote characters, since RFC 4180 escapes a quote by doubling it), or a last row
/// with fewer fields than the header and no line end after it.
fn check_complete(text: &str, rows: &[Vec<String>]) -> Result<(), String> {
    if text.bytes().filter(|&b| b == b'"').count() % 2 == 1 {
        return Err(
            "truncated CSV: a quoted field is not closed before the end of the file".into(),
        );
    }
    let ended = text.ends_with('\n') || text.ends_with('\r');
    if let (false, [header, .., last]) = (ended, rows) {
        if last.len() < header.len() {
            return Err(format!(
                "truncated CSV: the last row has {} of the header's {} fields and no line end",
                last.len(),
                header.len()
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cut_file_is_an_error() {
        assert!(read("a,b\n1,2\n3", false, false)
            .unwrap_err()
            .contains("truncated"));
        assert!(read("a,b\n1,\"x", false, false)
            .unwrap_err()
            .contains("quoted"));
        // A last row without a line end but with every field is whole.
        assert_eq!(
            read("a,b\n1,2", false, false).unwrap().unwrap().rows.len(),
            1
        );
        assert_eq!(
            read("a,b\n1\n", false, false).unwrap().unwrap().rows[0].len(),
            1
        );
    }

    #[test]
    fn quoting_is_rfc4180_and_round_trips() {
        let text = to_text([vec!["a", "b,c"], vec!["say \"hi\"", "1.5"]]);
        assert_eq!(text, "a,\"b,c\"\n\"say \"\"hi\"\"\",1.5\n");
        let rows = read(&text, false, false).unwrap().unwrap();
        assert_eq!(rows.header, ["a", "b,c"]);
        assert_eq!(rows.rows, [vec!["say \"hi\"", "1.5"]]);
        assert_eq!(rows.column("b,c"), Some(1));
    }

    #[test]
    fn blank_and_comment_lines_are_skipped() {
        let rows = read("# note\nT, Z\n\n  \n0.5, 1.1\n", true, true)
            .unwrap()
            .unwrap();
        assert_eq!(rows.header, ["T", "Z"]);
        assert_eq!(rows.rows, [vec!["0.5", "1.1"]]);
        assert_eq!(read("\n\n", false, false).unwrap(), None);
    }
}
