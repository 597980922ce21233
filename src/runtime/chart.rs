//! Charts (SVG or PNG by extension) of one quantity against another, one line per series,
//! with failed runs as distinct marks. Used by `cgnodes sweep` and the benchmarks.

use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

/// One line of a chart: points in the order to join them.
#[derive(Clone, Debug, Default)]
pub struct Series {
    /// Legend label.
    pub label: String,
    /// (x, y) points.
    pub points: Vec<(f64, f64)>,
}

/// What to draw.
#[derive(Clone, Debug, Default)]
pub struct Chart {
    /// Title above the plot.
    pub title: String,
    /// X axis label.
    pub x_label: String,
    /// Y axis label.
    pub y_label: String,
    /// Lines.
    pub series: Vec<Series>,
    /// Failed runs: an x position and a label (drawn as crosses along the top edge).
    pub failures: Vec<(f64, String)>,
    /// Logarithmic x axis.
    pub log_x: bool,
    /// Logarithmic y axis.
    pub log_y: bool,
}

/// Why a chart was not drawn.
#[derive(Debug, thiserror::Error)]
pub enum ChartError {
    /// Plotters could not draw it.
    #[error("{0}")]
    Draw(String),
    /// The PNG could not be encoded.
    #[error("{0}")]
    Encode(String),
    /// The file could not be written.
    #[error(transparent)]
    Write(#[from] std::io::Error),
    /// The file name asks for another format.
    #[error("{}: charts are .svg or .png, not '.{ext}'", path.display())]
    Format {
        path: std::path::PathBuf,
        ext: String,
    },
}

/// Draws `chart` to `path` (`.svg` or `.png`), written atomically.
pub fn draw(chart: &Chart, path: &Path) -> Result<(), ChartError> {
    cgnodes_formats::font::register_plot_font();
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    let (w, h) = (900u32, 600u32);
    match ext.as_str() {
        "svg" => {
            let mut text = String::new();
            {
                let root = SVGBackend::with_string(&mut text, (w, h)).into_drawing_area();
                draw_on(chart, &root)?;
                root.present()
                    .map_err(|e| ChartError::Draw(e.to_string()))?;
            }
            Ok(cgnodes_api::io::write_atomic(path, |wr| {
                wr.write_all(text.as_bytes())
            })?)
        }
        "png" => {
            let mut buf = vec![0u8; (w * h * 3) as usize];
            {
                let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
                draw_on(chart, &root)?;
                root.present()
                    .map_err(|e| ChartError::Draw(e.to_string()))?;
            }
            let bytes =
                cgnodes_formats::png::encode_png(w, h, 3, buf).map_err(ChartError::Encode)?;
            Ok(cgnodes_api::io::write_atomic(path, |wr| {
                wr.write_all(&bytes)
            })?)
        }
        other => Err(ChartError::Format {
            path: path.to_path_buf(),
            ext: other.to_string(),
        }),
    }
}

fn range(vals: impl Iterator<Item = f64>, log: bool) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in vals.filter(|v| v.is_finite() && (!log || *v > 0.0)) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return if log { (0.1, 10.0) } else { (0.0, 1.0) };
    }
    if log {
        (lo / 1.5, hi * 1.5)
    } else {
        let pad = if hi > lo {
            0.05 * (hi - lo)
        } else {
            lo.abs().max(1.0) * 0.1
        };
        (lo - pad, hi + pad)
    }
}

/// A short tick label: three significant digits, no trailing zeros, exponent form outside
/// 1e-3..1e5 (log axes otherwise print long, overlapping labels).
fn tick_label(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let a = v.abs();
    if !(1e-3..1e5).contains(&a) {
        return format!("{v:.2e}");
    }
    let decimals = (2 - a.log10().floor() as i32).max(0) as usize;
    let s = format!("{v:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// The legend corner that covers the fewest points: each point is placed in the unit
/// square of the plot (log axes in log space) and counted against a box of about the
/// legend's size in each corner; ties keep the order upper right, upper left, lower right,
/// lower left.
fn legend_corner(chart: &Chart, x: (f64, f64), y: (f64, f64)) -> SeriesLabelPosition {
    let unit = |v: f64, (lo, hi): (f64, f64), log: bool| {
        if log {
            (v.ln() - lo.ln()) / (hi.ln() - lo.ln())
        } else {
            (v - lo) / (hi - lo)
        }
    };
    let pts: Vec<(f64, f64)> = chart
        .series
        .iter()
        .flat_map(|s| s.points.iter())
        .map(|p| (unit(p.0, x, chart.log_x), unit(p.1, y, chart.log_y)))
        .filter(|p| p.0.is_finite() && p.1.is_finite())
        .collect();
    let rows = chart.series.len() + usize::from(!chart.failures.is_empty());
    let (w, h) = (0.3, (0.05 + 0.04 * rows as f64).min(0.6));
    let corners = [
        (SeriesLabelPosition::UpperRight, 1.0 - w, 1.0, 1.0 - h, 1.0),
        (SeriesLabelPosition::UpperLeft, 0.0, w, 1.0 - h, 1.0),
        (SeriesLabelPosition::LowerRight, 1.0 - w, 1.0, 0.0, h),
        (SeriesLabelPosition::LowerLeft, 0.0, w, 0.0, h),
    ];
    let covered = |c: &(SeriesLabelPosition, f64, f64, f64, f64)| {
        pts.iter()
            .filter(|p| (c.1..=c.2).contains(&p.0) && (c.3..=c.4).contains(&p.1))
            .count()
    };
    let best = corners
        .iter()
        .min_by_key(|c| covered(c))
        .expect("four corners");
    best.0.clone()
}

/// The points of series `s` that can be drawn: finite, and positive on a log axis.
fn plotted(chart: &Chart, s: &Series) -> Vec<(f64, f64)> {
    s.points
        .iter()
        .copied()
        .filter(|p| {
            p.0.is_finite()
                && p.1.is_finite()
                && (!chart.log_x || p.0 > 0.0)
                && (!chart.log_y || p.1 > 0.0)
        })
        .collect()
}

/// Where the failed runs' crosses go: at their x, in a row just below the top of the y range
/// `(y0, y1)`.
fn failure_marks(chart: &Chart, (y0, y1): (f64, f64)) -> Vec<(f64, f64)> {
    let top = if chart.log_y {
        y1 / 1.2
    } else {
        y1 - 0.02 * (y1 - y0)
    };
    chart
        .failures
        .iter()
        .filter(|f| f.0.is_finite() && (!chart.log_x || f.0 > 0.0))
        .map(|f| (f.0, top))
        .collect()
}

/// Draws `chart` on `root`: axes, a line per series, crosses for failed runs, the legend.
/// The body is a macro because each linear/log combination of the axes is another
/// coordinate type.
fn draw_on<DB: DrawingBackend>(
    chart: &Chart,
    root: &DrawingArea<DB, Shift>,
) -> Result<(), ChartError>
where
    DB::ErrorType: 'static,
{
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| ChartError::Draw(e.to_string());
    root.fill(&WHITE).map_err(e)?;
    let xs = chart
        .series
        .iter()
        .flat_map(|s| s.points.iter().map(|p| p.0))
        .chain(chart.failures.iter().map(|f| f.0));
    let (x0, x1) = range(xs, chart.log_x);
    let (y0, y1) = range(
        chart
            .series
            .iter()
            .flat_map(|s| s.points.iter().map(|p| p.1)),
        chart.log_y,
    );
    let mut b = ChartBuilder::on(root);
    b.caption(&chart.title, ("sans-serif", 22))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(70);
    macro_rules! body {
        ($ctx:expr) => {{
            let mut ctx = $ctx;
            ctx.configure_mesh()
                .x_desc(chart.x_label.as_str())
                .y_desc(chart.y_label.as_str())
                .x_labels(7)
                .y_labels(8)
                .x_label_formatter(&|v| tick_label(*v))
                .y_label_formatter(&|v| tick_label(*v))
                .label_style(("sans-serif", 14))
                .draw()
                .map_err(e)?;
            for (i, s) in chart.series.iter().enumerate() {
                let color = Palette99::pick(i).to_rgba();
                let pts = plotted(chart, s);
                ctx.draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))
                    .map_err(e)?
                    .label(s.label.as_str())
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
                    });
                ctx.draw_series(pts.iter().map(|&p| Circle::new(p, 4, color.filled())))
                    .map_err(e)?;
            }
            if !chart.failures.is_empty() {
                let pts = failure_marks(chart, (y0, y1));
                ctx.draw_series(pts.iter().map(|&p| Cross::new(p, 7, RED.stroke_width(3))))
                    .map_err(e)?
                    .label(format!("failed ({})", chart.failures.len()))
                    .legend(|(x, y)| Cross::new((x + 10, y), 6, RED.stroke_width(3)));
            }
            ctx.configure_series_labels()
                .position(legend_corner(chart, (x0, x1), (y0, y1)))
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .label_font(("sans-serif", 14))
                .draw()
                .map_err(e)?;
        }};
    }
    match (chart.log_x, chart.log_y) {
        (false, false) => body!(b.build_cartesian_2d(x0..x1, y0..y1).map_err(e)?),
        (true, false) => body!(b
            .build_cartesian_2d((x0..x1).log_scale(), y0..y1)
            .map_err(e)?),
        (false, true) => body!(b
            .build_cartesian_2d(x0..x1, (y0..y1).log_scale())
            .map_err(e)?),
        (true, true) => body!(b
            .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
            .map_err(e)?),
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tick_labels_are_short() {
        assert_eq!(tick_label(600.0), "600");
        assert_eq!(tick_label(0.61451), "0.615");
        assert_eq!(tick_label(2.5), "2.5");
        assert_eq!(tick_label(12345.0), "12345");
        assert_eq!(tick_label(1e-6), "1.00e-6");
        assert_eq!(tick_label(0.0), "0");
    }

    #[test]
    fn legend_avoids_the_corner_with_points() {
        let chart = |points: Vec<(f64, f64)>| Chart {
            series: vec![Series {
                label: "a".into(),
                points,
            }],
            ..Default::default()
        };
        let where_ = |c: &Chart| format!("{:?}", legend_corner(c, (0.0, 1.0), (0.0, 1.0)));
        // Points in the upper right push the legend to the upper left.
        let c = chart(vec![(0.95, 0.95), (0.9, 0.9), (0.5, 0.5)]);
        assert_eq!(where_(&c), "UpperLeft");
        // Points along the top push it down, to the emptier lower corner.
        let c = chart(vec![(0.05, 0.95), (0.95, 0.95), (0.9, 0.05)]);
        assert_eq!(where_(&c), "LowerLeft");
        // Nothing in the way: the usual upper right.
        assert_eq!(where_(&chart(vec![(0.5, 0.5)])), "UpperRight");
    }

    #[test]
    fn draws_svg_and_png() {
        let d = tempfile::tempdir().unwrap();
        let c = Chart {
            title: "error against time".into(),
            x_label: "ms".into(),
            y_label: "error".into(),
            series: vec![Series {
                label: "a".into(),
                points: vec![(1.0, 0.5), (10.0, 0.05), (100.0, 0.005)],
            }],
            failures: vec![(3.0, "unstable".into())],
            log_x: true,
            log_y: true,
        };
        draw(&c, &d.path().join("c.svg")).unwrap();
        let svg = std::fs::read_to_string(d.path().join("c.svg")).unwrap();
        assert!(
            svg.contains("<svg")
                && svg.contains("error against time")
                && svg.contains("failed (1)")
        );
        draw(&c, &d.path().join("c.png")).unwrap();
        let img = image::open(d.path().join("c.png")).unwrap();
        assert_eq!((img.width(), img.height()), (900, 600));
        assert!(draw(&c, &d.path().join("c.pdf")).is_err());
    }
}
