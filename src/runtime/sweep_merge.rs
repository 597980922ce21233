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
#[derive(PartialEq)]
struct Columns {
    vary: Vec<String>,
    measures: Vec<String>,
}

/// A part read: its columns and its rows.
struct Part {
    columns: Columns,
    rows: Vec<SweepRow>,
    shard: Option<Shard>,
    total: usize,
}

/// Merges parts given as `(name, CSV text)`: the spec (varied parameters with the values seen,
/// in order, and the measures; no graph) and the rows in the order of an unsharded sweep.
pub fn merge(parts: &[(String, String)]) -> Result<(SweepSpec, Vec<SweepRow>), String> {
    if parts.is_empty() {
        return Err("sweep-merge: no parts given".into());
    }
    let read: Vec<Part> = parts
        .iter()
        .map(|(name, text)| read_part(text).map_err(|e| format!("{name}: {e}")))
        .collect::<Result<_, _>>()?;
    let (first, first_name) = (&read[0], &parts[0].0);
    for (p, (name, _)) in read.iter().zip(parts).skip(1) {
        if p.columns != first.columns {
            return Err(format!(
                "mismatched columns: {name} has varied parameters [{}] and measures [{}], {first_name} has [{}] and [{}]; were they parts of the same sweep?",
                p.columns.vary.join(", "),
                p.columns.measures.join(", "),
                first.columns.vary.join(", "),
                first.columns.measures.join(", ")
            ));
        }
        if p.total != first.total && p.shard.is_some() && first.shard.is_some() {
            return Err(format!(
                "{name} belongs to a sweep of {} combinations, {first_name} to one of {}",
                p.total, first.total
            ));
        }
    }
    let total = read
        .iter()
        .find(|p| p.shard.is_some())
        .map_or(0, |p| p.total);
    let count = read.iter().find_map(|p| p.shard).map_or(1, |s| s.count);
    if let Some((p, name)) = read
        .iter()
        .zip(parts)
        .find(|(p, _)| p.shard.is_some_and(|s| s.count != count))
    {
        return Err(format!(
            "{}: shard {} is not one of {count} shards like the other parts",
            name.0,
            p.shard.unwrap_or_default()
        ));
    }
    // Every (combination, repeat) once.
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
                    describe(&first.columns.vary, &r.values),
                    r.repeat,
                    parts[other].0,
                    parts[pi].0
                ));
            }
        }
    }
    if !dups.is_empty() {
        let more = match dups.len() {
            n if n > 5 => format!("; and {} more", n - 5),
            _ => String::new(),
        };
        dups.truncate(5);
        return Err(format!("duplicated: {}{more}", dups.join("; ")));
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
        let by_shard: Vec<String> = missing
            .iter()
            .map(|(s, ks)| format!("shard {s}/{count} runs combinations {}", ks.join(", ")))
            .collect();
        return Err(format!(
            "missing combinations of {total}: {} (is its part missing or incomplete?)",
            by_shard.join("; ")
        ));
    }
    let cols = Columns {
        vary: first.columns.vary.clone(),
        measures: first.columns.measures.clone(),
    };
    let mut rows: Vec<SweepRow> = read.into_iter().flat_map(|p| p.rows).collect();
    rows.sort_by_key(|r| (r.combination, r.repeat));
    let mut vary: Vec<Vary> = cols
        .vary
        .iter()
        .map(|p| Vary {
            param: p.clone(),
            values: Vec::new(),
        })
        .collect();
    for r in &rows {
        for (v, x) in vary.iter_mut().zip(&r.values) {
            if !v.values.contains(x) {
                v.values.push(x.clone());
            }
        }
    }
    let spec = SweepSpec {
        vary,
        measure: cols.measures,
        repeat: repeats.max(1),
        ..Default::default()
    };
    Ok((spec, rows))
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

fn read_part(text: &str) -> Result<Part, String> {
    let csv = read(text, false, false)?.ok_or("empty file, no header")?;
    let h = &csv.header;
    if h.len() < 3 || h[..3] != SHARD_COLUMNS {
        return Err(format!(
            "not a part of a sharded sweep: its first columns are not {} (write parts with cgnodes sweep --shard I/N --csv)",
            SHARD_COLUMNS.join(", ")
        ));
    }
    let rep = h
        .iter()
        .position(|c| c == "repeat")
        .ok_or("no 'repeat' column")?;
    if h.len() < rep + FIXED.len() || h[rep..rep + FIXED.len()] != FIXED {
        return Err(format!(
            "expected the columns {} after the varied parameters",
            FIXED.join(", ")
        ));
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
        let at = |what: &str| format!("row {}: {what}", line + 2);
        if f.len() != h.len() {
            return Err(at(&format!(
                "{} fields, the header has {}",
                f.len(),
                h.len()
            )));
        }
        let s = Shard::parse(&f[0]).map_err(|e| at(&e))?;
        if shard.is_some_and(|x| x != s) {
            return Err(at("rows of two shards in one part"));
        }
        shard = Some(s);
        let num = |i: usize| -> Result<usize, String> {
            f[i].parse()
                .map_err(|_| at(&format!("{} '{}' is not a whole number", h[i], f[i])))
        };
        let (k, t) = (num(1)?, num(2)?);
        if k >= t || !s.takes(k) || (total != 0 && t != total) {
            return Err(at(&format!(
                "combination {k} of {t} does not belong to shard {s}"
            )));
        }
        total = t;
        let float = |i: usize| -> Result<f64, String> {
            if f[i].is_empty() {
                return Ok(f64::NAN);
            }
            f[i].parse()
                .map_err(|_| at(&format!("{} '{}' is not a number", h[i], f[i])))
        };
        let mut node_ms = BTreeMap::new();
        for (i, name) in h.iter().enumerate().take(ms_end).skip(ms_start) {
            node_ms.insert(name[3..].to_string(), float(i)?);
        }
        rows.push(SweepRow {
            combination: k,
            values: f[3..rep].iter().map(|s| value_of(s)).collect(),
            repeat: num(rep)?,
            ok: f[rep + 1] == "ok",
            error_kind: f[rep + 2].clone(),
            error: f[rep + 3].clone(),
            total_ms: float(rep + 4)?,
            node_ms,
            measures: (ms_end..h.len()).map(float).collect::<Result<_, _>>()?,
        });
    }
    // The varied values of two rows of one combination agree.
    let mut by_combo: BTreeMap<usize, &Vec<serde_json::Value>> = BTreeMap::new();
    for r in &rows {
        if let Some(v) = by_combo.insert(r.combination, &r.values) {
            if v != &r.values {
                return Err(format!(
                    "combination {} has two sets of varied values",
                    r.combination
                ));
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
