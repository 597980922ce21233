//! What a sweep writes from its rows: the CSV table and the chart of one recorded quantity
//! against another.

use super::{SweepRow, SweepSpec};
use crate::chart::{Chart, Series};

/// A chart axis that names nothing a sweep records.
#[derive(Debug, thiserror::Error)]
pub enum AxisError {
    #[error("nothing to plot: give --measure")]
    NothingToPlot,
    #[error("no node '{0}' for the time axis")]
    NoNode(String),
    #[error("'{0}' has non-numeric values")]
    NotNumeric(String),
    #[error("'{0}' is neither time, time:NODE, a measure nor a varied parameter")]
    Unknown(String),
}

/// CSV text of a sweep's rows: the varied values, repeat, status, error, total and per-node
/// wall times, then the measures (empty when not finite).
pub fn to_csv(spec: &SweepSpec, rows: &[SweepRow]) -> String {
    let nodes: Vec<String> = rows
        .first()
        .map(|r| r.node_ms.keys().cloned().collect())
        .unwrap_or_default();
    let shard_head = spec
        .shard
        .map(|_| ["shard", "combination", "combinations"].map(String::from));
    let total: usize = spec.vary.iter().map(|v| v.values.len()).product();
    let mut head: Vec<String> = shard_head.into_iter().flatten().collect();
    head.extend(spec.vary.iter().map(|v| v.param.clone()));
    head.extend(["repeat", "status", "error_kind", "error", "total_ms"].map(String::from));
    head.extend(nodes.iter().map(|n| format!("ms:{n}")));
    head.extend(spec.measure.iter().cloned());
    let records = rows.iter().map(|r| {
        let mut f: Vec<String> = match spec.shard {
            Some(s) => vec![s.to_string(), r.combination.to_string(), total.to_string()],
            None => Vec::new(),
        };
        f.extend(r.values.iter().map(value_text));
        f.push(r.repeat.to_string());
        f.push(if r.ok { "ok".into() } else { "failed".into() });
        f.push(r.error_kind.clone());
        f.push(r.error.clone());
        f.push(format!("{:.4}", r.total_ms));
        for n in &nodes {
            f.push(format!("{:.4}", r.node_ms.get(n).copied().unwrap_or(0.0)));
        }
        for m in &r.measures {
            f.push(if m.is_finite() {
                format!("{m}")
            } else {
                String::new()
            });
        }
        f
    });
    cgnodes_api::io::csv::to_text(std::iter::once(head).chain(records))
}

/// A varied value as text: strings as they are, anything else as JSON.
pub fn value_text(v: &serde_json::Value) -> String {
    match v {
        serde_json::Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

/// The chart of a sweep: y against x, one series per value of the series parameter.
pub fn to_chart(spec: &SweepSpec, rows: &[SweepRow]) -> Result<Chart, AxisError> {
    let xs = spec.x.clone().unwrap_or_else(|| "time".into());
    let ys = spec
        .y
        .clone()
        .or_else(|| spec.measure.first().cloned())
        .ok_or(AxisError::NothingToPlot)?;
    let axis = |name: &str, r: &SweepRow| axis(spec, name, r);
    let series_param = spec.series.clone().or_else(|| {
        spec.vary
            .iter()
            .find(|v| v.values.iter().any(|x| x.is_string()) && v.param != xs)
            .map(|v| v.param.clone())
    });
    let sidx = series_param
        .as_ref()
        .and_then(|p| spec.vary.iter().position(|v| &v.param == p));
    let mut series: Vec<Series> = Vec::new();
    let mut failures = Vec::new();
    for r in rows {
        let x = axis(&xs, r)?;
        if !r.ok {
            failures.push((x, r.error_kind.clone()));
            continue;
        }
        let y = axis(&ys, r)?;
        let label = match sidx {
            Some(k) => value_text(&r.values[k]),
            None => ys.clone(),
        };
        match series.iter_mut().find(|s| s.label == label) {
            Some(s) => s.points.push((x, y)),
            None => series.push(Series {
                label,
                points: vec![(x, y)],
            }),
        }
    }
    for s in &mut series {
        s.points.sort_by(|a, b| a.0.total_cmp(&b.0));
    }
    let x_label = match xs.as_str() {
        "time" => "wall time (ms)".to_string(),
        t if t.starts_with("time:") => format!("{} wall time (ms)", &t[5..]),
        other => other.to_string(),
    };
    Ok(Chart {
        title: spec
            .title
            .clone()
            .unwrap_or_else(|| format!("{ys} against {x_label}")),
        x_label,
        y_label: ys,
        series,
        failures,
        log_x: spec.log_x,
        log_y: spec.log_y,
    })
}

/// The value of axis `name` (`time`, `time:NODE`, a measure or a varied parameter) in row `r`.
fn axis(spec: &SweepSpec, name: &str, r: &SweepRow) -> Result<f64, AxisError> {
    if name == "time" {
        return Ok(r.total_ms);
    }
    if let Some(node) = name.strip_prefix("time:") {
        return r
            .node_ms
            .get(node)
            .copied()
            .ok_or_else(|| AxisError::NoNode(node.to_string()));
    }
    if let Some(k) = spec.measure.iter().position(|m| m == name) {
        return Ok(r.measures[k]);
    }
    if let Some(k) = spec.vary.iter().position(|v| v.param == name) {
        return r.values[k]
            .as_f64()
            .ok_or_else(|| AxisError::NotNumeric(name.to_string()));
    }
    Err(AxisError::Unknown(name.to_string()))
}
