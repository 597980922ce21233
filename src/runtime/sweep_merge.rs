//! `cgnodes sweep-merge`: joins the CSV parts of a sharded sweep (`cgnodes sweep --shard I/N`)
//! back into the rows an unsharded sweep has, in the same order, after checking that every
//! combination (and every repeat of it) is present exactly once and that the parts have the
//! same columns. The caller writes them with `sweep::to_csv` and `sweep::to_chart`, so the
//! merged CSV and chart are those of one unsharded run.

use crate::shard::Shard;
use crate::sweep::{value_text, SweepRow, SweepSpec, Vary};
use cgnodes_api::io::csv::read;
use std::collections::BTreeMap;

/// The first columns of a part: its shard, the combination's index in the whole grid, and
/// how many combinations the grid has.
const SHARD_COLUMNS: [&str; 3] = ["shard", "combination", "combinations"];
/// Columns between the varied parameters and the per-node times.
const FIXED: [&str; 5] = ["repeat", "status", "error_kind", "error", "total_ms"];

/// The columns of one part that must agree between parts (per-node times may differ: they
/// come from the first run of each part).
#[derive(Clone, Debug, PartialEq)]
pub struct Columns {
    /// The varied parameters.
    pub vary: Vec<String>,
    /// The measures.
    pub measures: Vec<String>,
}

/// A part read: its columns and its rows.
struct Part {
    columns: Columns,
    rows: Vec<SweepRow>,
    shard: Option<Shard>,
    total: usize,
}

/// Why parts did not merge.
#[derive(Debug, thiserror::Error)]
pub enum MergeError {
    #[error("sweep-merge: no parts given")]
    NoParts,
    /// One part did not read.
    #[error("{part}: {problem}")]
    Part { part: String, problem: PartError },
    /// Two parts have different varied parameters or measures.
    #[error(
        "mismatched columns: {part} has varied parameters [{}] and measures [{}], {first} has [{}] and [{}]; were they parts of the same sweep?",
        columns.vary.join(", "), columns.measures.join(", "), first_columns.vary.join(", "), first_columns.measures.join(", ")
    )]
    Columns {
        part: String,
        columns: Box<Columns>,
        first: String,
        first_columns: Box<Columns>,
    },
    /// Two parts belong to sweeps of different sizes.
    #[error("{part} belongs to a sweep of {total} combinations, {first} to one of {first_total}")]
    Total {
        part: String,
        total: usize,
        first: String,
        first_total: usize,
    },
    /// A part comes from a split into another number of shards.
    #[error("{part}: shard {shard} is not one of {count} shards like the other parts")]
    ShardCount {
        part: String,
        shard: Shard,
        count: usize,
    },
    /// Runs present in two parts, one line each.
    #[error("duplicated: {}", at_most_five(.0))]
    Duplicated(Vec<String>),
    /// Combinations no part has, one line per shard.
    #[error("missing combinations of {total}: {} (is its part missing or incomplete?)", by_shard.join("; "))]
    Missing { total: usize, by_shard: Vec<String> },
}

/// The first five lines, and how many more there are.
fn at_most_five(lines: &[String]) -> String {
    let more = match lines.len() {
        n if n > 5 => format!("; and {} more", n - 5),
        _ => String::new(),
    };
    format!("{}{more}", lines[..lines.len().min(5)].join("; "))
}

/// Why one part did not read.
#[derive(Debug, thiserror::Error)]
pub enum PartError {
    /// Not CSV.
    #[error("{0}")]
    Csv(String),
    #[error("empty file, no header")]
    Empty,
    #[error("not a part of a sharded sweep: its first columns are not {} (write parts with cgnodes sweep --shard I/N --csv)", SHARD_COLUMNS.join(", "))]
    NotAPart,
    #[error("no 'repeat' column")]
    NoRepeat,
    #[error("expected the columns {} after the varied parameters", FIXED.join(", "))]
    Fixed,
    /// A row (numbered from 1 at the header) is wrong.
    #[error("row {line}: {problem}")]
    Row { line: usize, problem: RowError },
    #[error("combination {0} has two sets of varied values")]
    TwoValueSets(usize),
}

/// What is wrong with one row of a part.
#[derive(Debug, thiserror::Error)]
pub enum RowError {
    #[error("{fields} fields, the header has {header}")]
    Fields { fields: usize, header: usize },
    #[error("{0}")]
    Shard(crate::shard::ShardError),
    #[error("rows of two shards in one part")]
    TwoShards,
    #[error("{column} '{text}' is not a whole number")]
    NotWhole { column: String, text: String },
    #[error("{column} '{text}' is not a number")]
    NotNumber { column: String, text: String },
    #[error("combination {combination} of {total} does not belong to shard {shard}")]
    NotInShard {
        combination: usize,
        total: usize,
        shard: Shard,
    },
}

/// Merges parts given as `(name, CSV text)`: the spec (varied parameters with the values seen,
/// in order, and the measures; no graph) and the rows in the order of an unsharded sweep.
pub fn merge(parts: &[(String, String)]) -> Result<(SweepSpec, Vec<SweepRow>), MergeError> {
    if parts.is_empty() {
        return Err(MergeError::NoParts);
    }
    let read: Vec<Part> = parts
        .iter()
        .map(|(name, text)| {
            read_part(text).map_err(|problem| MergeError::Part {
                part: name.clone(),
                problem,
            })
        })
        .collect::<Result<_, _>>()?;
    let names: Vec<&str> = parts.iter().map(|(n, _)| n.as_str()).collect();
    let (total, count) = check_alike(&read, &names)?;
    let repeats = check_each_once(&read, &names, total, count)?;
    let vary_names = read[0].columns.vary.clone();
    let measure = read[0].columns.measures.clone();
    let mut rows: Vec<SweepRow> = read.into_iter().flat_map(|p| p.rows).collect();
    rows.sort_by_key(|r| (r.combination, r.repeat));
    let spec = SweepSpec {
        vary: values_seen(vary_names, &rows),
        measure,
        repeat: repeats.max(1),
        ..Default::default()
    };
    Ok((spec, rows))
}

/// The parts come from one sweep: the same columns, the same number of combinations and of
/// shards. Returns (combinations, shards).
fn check_alike(read: &[Part], names: &[&str]) -> Result<(usize, usize), MergeError> {
    let first = &read[0];
    for (p, name) in read.iter().zip(names).skip(1) {
        if p.columns != first.columns {
            return Err(MergeError::Columns {
                part: name.to_string(),
                columns: Box::new(p.columns.clone()),
                first: names[0].to_string(),
                first_columns: Box::new(first.columns.clone()),
            });
        }
        if p.total != first.total && p.shard.is_some() && first.shard.is_some() {
            return Err(MergeError::Total {
                part: name.to_string(),
                total: p.total,
                first: names[0].to_string(),
                first_total: first.total,
            });
        }
    }
    let total = read
        .iter()
        .find(|p| p.shard.is_some())
        .map_or(0, |p| p.total);
    let count = read.iter().find_map(|p| p.shard).map_or(1, |s| s.count);
    if let Some((p, name)) = read
        .iter()
        .zip(names)
        .find(|(p, _)| p.shard.is_some_and(|s| s.count != count))
    {
        return Err(MergeError::ShardCount {
            part: name.to_string(),
            shard: p.shard.unwrap_or_default(),
            count,
        });
    }
    Ok((total, count))
}

/// Every (combination, repeat) of the `total` combinations is in exactly one part. Returns
/// the number of repeats.
fn check_each_once(
    read: &[Part],
    names: &[&str],
    total: usize,
    count: usize,
) -> Result<usize, MergeError> {
    let mut seen: BTreeMap<(usize, usize), usize> = BTreeMap::new();
    let mut repeats = 0;
    let mut dups = Vec::new();
    for (pi, p) in read.iter().enumerate() {
        for r in &p.rows {
            repeats = repeats.max(r.repeat + 1);
            if let Some(other) = seen.insert((r.combination, r.repeat), pi) {
                dups.push(format!(
                    "combination {} ({}) repeat {} is in both {} and {}",
                    r.combination,
                    describe(&read[0].columns.vary, &r.values),
                    r.repeat,
                    names[other],
                    names[pi]
                ));
            }
        }
    }
    if !dups.is_empty() {
        return Err(MergeError::Duplicated(dups));
    }
    let mut missing: BTreeMap<usize, Vec<String>> = BTreeMap::new();
    for k in 0..total {
        let absent: Vec<usize> = (0..repeats.max(1))
            .filter(|&r| !seen.contains_key(&(k, r)))
            .collect();
        if absent.is_empty() {
            continue;
        }
        let what = if absent.len() == repeats.max(1) {
            format!("{k}")
        } else {
            let reps: Vec<String> = absent.iter().map(|r| r.to_string()).collect();
            format!("{k} (repeat {})", reps.join(", "))
        };
        missing.entry(k % count).or_default().push(what);
    }
    if !missing.is_empty() {
        return Err(MergeError::Missing {
            total,
            by_shard: missing
                .iter()
                .map(|(s, ks)| format!("shard {s}/{count} runs combinations {}", ks.join(", ")))
                .collect(),
        });
    }
    Ok(repeats)
}

/// Each varied parameter with the values the rows have, in the order they first appear.
fn values_seen(params: Vec<String>, rows: &[SweepRow]) -> Vec<Vary> {
    let mut vary: Vec<Vary> = params
        .into_iter()
        .map(|param| Vary {
            param,
            values: Vec::new(),
        })
        .collect();
    for r in rows {
        for (v, x) in vary.iter_mut().zip(&r.values) {
            if !v.values.contains(x) {
                v.values.push(x.clone());
            }
        }
    }
    vary
}

/// `a=1, b=x` for a combination's varied values.
fn describe(params: &[String], values: &[serde_json::Value]) -> String {
    params
        .iter()
        .zip(values)
        .map(|(p, v)| format!("{p}={}", value_text(v)))
        .collect::<Vec<_>>()
        .join(", ")
}

/// A varied value read back from its text (`sweep::value_text` inverted: JSON when it parses,
/// else a string).
fn value_of(s: &str) -> serde_json::Value {
    serde_json::from_str(s).unwrap_or_else(|_| serde_json::Value::String(s.to_string()))
}

/// Reads one part: its columns, and its rows checked against them and its shard.
fn read_part(text: &str) -> Result<Part, PartError> {
    let csv = read(text, false, false)
        .map_err(PartError::Csv)?
        .ok_or(PartError::Empty)?;
    let h = &csv.header;
    if h.len() < 3 || h[..3] != SHARD_COLUMNS {
        return Err(PartError::NotAPart);
    }
    let rep = h
        .iter()
        .position(|c| c == "repeat")
        .ok_or(PartError::NoRepeat)?;
    if h.len() < rep + FIXED.len() || h[rep..rep + FIXED.len()] != FIXED {
        return Err(PartError::Fixed);
    }
    let ms_start = rep + FIXED.len();
    let ms_end = ms_start
        + h[ms_start..]
            .iter()
            .take_while(|c| c.starts_with("ms:"))
            .count();
    let columns = Columns {
        vary: h[3..rep].to_vec(),
        measures: h[ms_end..].to_vec(),
    };
    let mut shard = None;
    let mut total = 0;
    let mut rows = Vec::new();
    for (line, f) in csv.rows.iter().enumerate() {
        let layout = Layout {
            header: h,
            rep,
            ms: ms_start..ms_end,
        };
        let (row, s) = read_row(&layout, f, shard, total).map_err(|problem| PartError::Row {
            line: line + 2,
            problem,
        })?;
        shard = Some(s);
        total = row.1;
        rows.push(row.0);
    }
    // The varied values of two rows of one combination agree.
    let mut by_combo: BTreeMap<usize, &Vec<serde_json::Value>> = BTreeMap::new();
    for r in &rows {
        if let Some(v) = by_combo.insert(r.combination, &r.values) {
            if v != &r.values {
                return Err(PartError::TwoValueSets(r.combination));
            }
        }
    }
    Ok(Part {
        columns,
        rows,
        shard,
        total,
    })
}

/// Where a part's columns are: the header, the `repeat` column, the per-node times.
struct Layout<'a> {
    header: &'a [String],
    rep: usize,
    ms: std::ops::Range<usize>,
}

/// One row `f` of a part whose rows so far have `shard` and `total` combinations: the row
/// with its total, and its shard.
fn read_row(
    l: &Layout,
    f: &[String],
    shard: Option<Shard>,
    total: usize,
) -> Result<((SweepRow, usize), Shard), RowError> {
    let (h, rep) = (l.header, l.rep);
    if f.len() != h.len() {
        return Err(RowError::Fields {
            fields: f.len(),
            header: h.len(),
        });
    }
    let s = Shard::parse(&f[0]).map_err(RowError::Shard)?;
    if shard.is_some_and(|x| x != s) {
        return Err(RowError::TwoShards);
    }
    let num = |i: usize| -> Result<usize, RowError> {
        f[i].parse().map_err(|_| RowError::NotWhole {
            column: h[i].clone(),
            text: f[i].clone(),
        })
    };
    let (k, t) = (num(1)?, num(2)?);
    if k >= t || !s.takes(k) || (total != 0 && t != total) {
        return Err(RowError::NotInShard {
            combination: k,
            total: t,
            shard: s,
        });
    }
    let float = |i: usize| -> Result<f64, RowError> {
        if f[i].is_empty() {
            return Ok(f64::NAN);
        }
        f[i].parse().map_err(|_| RowError::NotNumber {
            column: h[i].clone(),
            text: f[i].clone(),
        })
    };
    let mut node_ms = BTreeMap::new();
    for i in l.ms.clone() {
        node_ms.insert(h[i][3..].to_string(), float(i)?);
    }
    let row = SweepRow {
        combination: k,
        values: f[3..rep].iter().map(|s| value_of(s)).collect(),
        repeat: num(rep)?,
        ok: f[rep + 1] == "ok",
        error_kind: f[rep + 2].clone(),
        error: f[rep + 3].clone(),
        total_ms: float(rep + 4)?,
        node_ms,
        measures: (l.ms.end..h.len()).map(float).collect::<Result<_, _>>()?,
    };
    Ok(((row, t), s))
}
