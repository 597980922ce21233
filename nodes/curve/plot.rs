//! `plot`: up to eight series of 2-D points drawn into a PNG or SVG with plotters: lines for
//! curves, markers for data points, a legend, and free or equal axes (equal: one unit is as
//! many pixels along x as along y, so circles look round).

use cgnodes_api::prelude::*;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::Color as _;
use std::path::Path;

/// The number of series sockets.
pub const MAX_SERIES: usize = 8;

/// How a series is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Style {
    /// A polyline through the points in order.
    Line,
    /// A marker at every point.
    Markers,
    /// Both.
    LineMarkers,
}

impl Choice for Style {
    const CHOICES: &'static [(&'static str, Self)] = &[
        ("line", Style::Line),
        ("markers", Style::Markers),
        ("line_markers", Style::LineMarkers),
    ];
}

/// The axes' scaling.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Axes {
    /// Each axis fits its data.
    Free,
    /// Equal units on both axes.
    Equal,
}

impl Choice for Axes {
    const CHOICES: &'static [(&'static str, Self)] =
        &[("free", Axes::Free), ("equal", Axes::Equal)];
}

/// One series.
#[derive(Clone, Debug)]
pub struct PlotSeries {
    /// Legend label (none when empty).
    pub label: String,
    /// The points.
    pub points: Vec<[f64; 2]>,
    /// How to draw them.
    pub style: Style,
    /// A class label per point: markers coloured by class, one legend entry per class.
    pub classes: Option<Vec<i64>>,
}

/// What to draw.
#[derive(Clone, Debug)]
pub struct Plot {
    /// Title above the plot.
    pub title: String,
    /// Axis labels.
    pub x_label: String,
    /// Axis labels.
    pub y_label: String,
    /// The series, in drawing order.
    pub series: Vec<PlotSeries>,
    /// Free or equal axes.
    pub axes: Axes,
    /// Size in pixels.
    pub size: (u32, u32),
    /// A classifier of two features whose decision regions fill the background.
    pub regions: Option<Arc<Model>>,
}

/// The output formats.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PlotFormat {
    /// Vector.
    Svg,
    /// 8-bit RGB.
    Png,
}

impl PlotFormat {
    /// The format of a path's extension.
    pub fn from_path(p: &Path) -> Option<PlotFormat> {
        match p.extension()?.to_str()?.to_ascii_lowercase().as_str() {
            "svg" => Some(PlotFormat::Svg),
            "png" => Some(PlotFormat::Png),
            _ => None,
        }
    }
}

/// Ten distinguishable colours (matplotlib's "tab10").
const COLORS: [(u8, u8, u8); 8] = [
    (31, 119, 180),
    (255, 127, 14),
    (44, 160, 44),
    (214, 39, 40),
    (148, 103, 189),
    (140, 86, 75),
    (227, 119, 194),
    (23, 190, 207),
];

/// The data's bounding box, padded by 5 % (a unit box around a single point).
fn bounds(plot: &Plot) -> ((f64, f64), (f64, f64)) {
    let mut b = [
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    ];
    for p in plot.series.iter().flat_map(|s| &s.points) {
        if p[0].is_finite() && p[1].is_finite() {
            b = [
                b[0].min(p[0]),
                b[1].max(p[0]),
                b[2].min(p[1]),
                b[3].max(p[1]),
            ];
        }
    }
    let pad = |lo: f64, hi: f64| {
        if !lo.is_finite() {
            (0.0, 1.0)
        } else if hi > lo {
            let d = 0.05 * (hi - lo);
            (lo - d, hi + d)
        } else {
            (lo - 0.5, hi + 0.5)
        }
    };
    (pad(b[0], b[1]), pad(b[2], b[3]))
}

/// Widens the range with fewer units per pixel so both axes have the same.
fn equalize(x: (f64, f64), y: (f64, f64), px: (u32, u32)) -> ((f64, f64), (f64, f64)) {
    let (w, h) = (px.0.max(1) as f64, px.1.max(1) as f64);
    let (ux, uy) = ((x.1 - x.0) / w, (y.1 - y.0) / h);
    let grow = |r: (f64, f64), u: f64, n: f64| {
        let c = 0.5 * (r.0 + r.1);
        (c - 0.5 * u * n, c + 0.5 * u * n)
    };
    if ux > uy {
        (x, grow(y, ux, h))
    } else {
        (grow(x, uy, w), y)
    }
}

/// The chart layout shared by the measuring pass and the drawing pass.
fn chart_builder<'a, 'b, DB: DrawingBackend>(
    root: &'a DrawingArea<DB, Shift>,
    title: &'b str,
) -> ChartBuilder<'a, 'b, DB> {
    let mut b = ChartBuilder::on(root);
    b.caption(title, ("sans-serif", 22))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(60);
    b
}

fn draw_on<DB: DrawingBackend>(plot: &Plot, root: &DrawingArea<DB, Shift>) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| PlotError::Draw(e.to_string());
    root.fill(&WHITE).map_err(e)?;
    let (mut x, mut y) = bounds(plot);
    let builder = |root| chart_builder(root, &plot.title);
    if plot.axes == Axes::Equal {
        // The plotting area's size does not depend on the ranges: measure it first.
        let probe = builder(root)
            .build_cartesian_2d(0.0..1.0, 0.0..1.0)
            .map_err(e)?;
        let px = probe.plotting_area().dim_in_pixel();
        (x, y) = equalize(x, y, px);
        root.fill(&WHITE).map_err(e)?;
    }
    let mut ctx = builder(root)
        .build_cartesian_2d(x.0..x.1, y.0..y.1)
        .map_err(e)?;
    if let Some(m) = &plot.regions {
        let (pw, ph) = ctx.plotting_area().dim_in_pixel();
        let rects = region_runs(m, x, y, (pw / 3).max(1) as usize, (ph / 3).max(1) as usize)
            .map_err(PlotError::Regions)?;
        ctx.draw_series(rects.into_iter().map(|(k, a, b)| {
            let (r, g, bl) = COLORS[k % COLORS.len()];
            Rectangle::new([a, b], RGBColor(r, g, bl).mix(0.22).filled())
        }))
        .map_err(e)?;
    }
    ctx.configure_mesh()
        .x_desc(plot.x_label.as_str())
        .y_desc(plot.y_label.as_str())
        .label_style(("sans-serif", 14))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(e)?;
    let mut any_label = false;
    for (i, s) in plot.series.iter().enumerate() {
        let (r, g, b) = COLORS[i % COLORS.len()];
        let color = RGBColor(r, g, b);
        let pts: Vec<(f64, f64)> = s
            .points
            .iter()
            .filter(|p| p[0].is_finite() && p[1].is_finite())
            .map(|p| (p[0], p[1]))
            .collect();
        if let Some(labels) = &s.classes {
            let classes = class_list(plot.regions.as_deref(), labels);
            for (k, c) in classes.iter().enumerate() {
                let (r, g, b) = COLORS[k % COLORS.len()];
                let color = RGBColor(r, g, b);
                let group = s
                    .points
                    .iter()
                    .zip(labels)
                    .filter(|(p, l)| *l == c && p[0].is_finite() && p[1].is_finite())
                    .map(|(p, _)| Circle::new((p[0], p[1]), 4, color.filled()));
                let a = ctx.draw_series(group).map_err(e)?;
                any_label = true;
                a.label(format!("{} {c}", s.label).trim().to_string())
                    .legend(move |(x, y)| Circle::new((x + 10, y), 4, color.filled()));
            }
            continue;
        }
        let line = matches!(s.style, Style::Line | Style::LineMarkers);
        let markers = matches!(s.style, Style::Markers | Style::LineMarkers);
        if line {
            let a = ctx
                .draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))
                .map_err(e)?;
            if !s.label.is_empty() {
                any_label = true;
                a.label(s.label.as_str()).legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
                });
            }
        }
        if markers {
            let a = ctx
                .draw_series(pts.iter().map(|&p| Circle::new(p, 4, color.filled())))
                .map_err(e)?;
            if !s.label.is_empty() && !line {
                any_label = true;
                a.label(s.label.as_str())
                    .legend(move |(x, y)| Circle::new((x + 10, y), 4, color.filled()));
            }
        }
    }
    if any_label {
        ctx.configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 14))
            .draw()
            .map_err(e)?;
    }
    Ok(())
}

/// The classes whose colours are used: the model's output classes, else the labels' distinct
/// values in increasing order.
fn class_list(model: Option<&Model>, labels: &[i64]) -> Vec<i64> {
    match model {
        Some(m) => m.classes.clone(),
        None => {
            let mut c = labels.to_vec();
            c.sort_unstable();
            c.dedup();
            c
        }
    }
}

/// Runs of equal predicted class along the rows of an `nx` x `ny` grid over the box
/// `x` x `y`: (class index, one corner, the opposite corner), so a region costs a few
/// rectangles per row rather than one per cell.
type Run = (usize, (f64, f64), (f64, f64));

fn region_runs(
    m: &Model,
    x: (f64, f64),
    y: (f64, f64),
    nx: usize,
    ny: usize,
) -> Result<Vec<Run>, String> {
    if m.features.len() != 2 {
        return Err(format!(
            "need a model of 2 features, this one has {}",
            m.features.len()
        ));
    }
    let (dx, dy) = ((x.1 - x.0) / nx as f64, (y.1 - y.0) / ny as f64);
    let cells: Vec<Vec<f64>> = (0..ny)
        .flat_map(|j| {
            (0..nx).map(move |i| vec![x.0 + (i as f64 + 0.5) * dx, y.0 + (j as f64 + 0.5) * dy])
        })
        .collect();
    let pred = cgnodes_nn::dataset::predict(m, &cells).map_err(|e| e.to_string())?;
    let index = |v: i64| m.classes.iter().position(|c| *c == v).unwrap_or(0);
    let mut runs = Vec::new();
    for j in 0..ny {
        let row = &pred[j * nx..(j + 1) * nx];
        let mut start = 0;
        for i in 1..=nx {
            if i == nx || row[i] != row[start] {
                let (y0, y1) = (y.0 + j as f64 * dy, y.0 + (j + 1) as f64 * dy);
                runs.push((
                    index(row[start]),
                    (x.0 + start as f64 * dx, y0),
                    (x.0 + i as f64 * dx, y1),
                ));
                start = i;
            }
        }
    }
    Ok(runs)
}

/// Why a plot could not be drawn, by what it concerns.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum PlotError {
    /// The decision regions of the classifier could not be drawn.
    #[error("decision regions: {0}")]
    Regions(String),
    /// Drawing or encoding the chart failed.
    #[error("{0}")]
    Draw(String),
}

impl PlotError {
    /// The input socket the error is about: `model` for the regions, else `path`.
    pub fn socket(&self) -> &'static str {
        match self {
            PlotError::Regions(_) => "model",
            PlotError::Draw(_) => "path",
        }
    }
}

/// Draws `plot` as file bytes in `format`.
pub fn render_plot(plot: &Plot, format: PlotFormat) -> Result<Vec<u8>, PlotError> {
    cgnodes_formats::font::register_plot_font();
    let (w, h) = plot.size;
    match format {
        PlotFormat::Svg => {
            let mut text = String::new();
            {
                let root = SVGBackend::with_string(&mut text, (w, h)).into_drawing_area();
                draw_on(plot, &root)?;
                root.present().map_err(|e| PlotError::Draw(e.to_string()))?;
            }
            Ok(text.into_bytes())
        }
        PlotFormat::Png => {
            let mut buf = vec![0u8; w as usize * h as usize * 3];
            {
                let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
                draw_on(plot, &root)?;
                root.present().map_err(|e| PlotError::Draw(e.to_string()))?;
            }
            cgnodes_formats::png::encode_png(w, h, 3, buf).map_err(PlotError::Draw)
        }
    }
}

fn declare(b: &mut NodeBuilder) {
    b.doc(
        "Draws up to 8 series of points (lines or markers, with legend labels) into a PNG or SVG.",
    );
    b.sink();
    for k in 1..=MAX_SERIES {
        b.add_input::<Vec<[f64; 2]>>(&format!("series_{k}"))
            .optional()
            .doc("Points (x, y) of one series.");
        b.add_input::<String>(&format!("label_{k}"))
            .default("")
            .doc("Its legend label (none when empty).");
        b.add_choice::<Style>(&format!("style_{k}"))
            .doc("line, markers or line_markers.");
    }
    b.add_input::<Vec<i64>>("classes_1")
        .optional()
        .doc("A class label per point of series_1: markers coloured by class.");
    b.add_input::<Model>("model")
        .optional()
        .doc("A classifier of two features: its decision regions fill the background.");
    b.add_input::<String>("title").default("");
    b.add_input::<String>("x_label").default("x");
    b.add_input::<String>("y_label").default("y");
    b.add_choice::<Axes>("axes")
        .doc("free: each axis fits its data; equal: the same units on both.");
    b.add_input::<i64>("width")
        .default(900)
        .range(100.0, 8000.0);
    b.add_input::<i64>("height")
        .default(600)
        .range(100.0, 8000.0);
    b.add_input::<String>("path")
        .file_out()
        .doc("Output file (.png or .svg), under the output directory.");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let mut series = Vec::new();
    for k in 1..=MAX_SERIES {
        if let Some(points) = ctx.input_opt::<Vec<[f64; 2]>>(&format!("series_{k}"))? {
            series.push(PlotSeries {
                label: ctx.input(&format!("label_{k}"))?,
                points,
                style: ctx.choice(&format!("style_{k}"))?,
                classes: None,
            });
        }
    }
    if let Some(c) = ctx.input_opt::<Vec<i64>>("classes_1")? {
        match series.first_mut() {
            Some(s) if s.points.len() == c.len() => s.classes = Some(c),
            _ => {
                return Err(NodeError::invalid(
                    "classes_1",
                    "needs series_1 with one label per point",
                ))
            }
        }
    }
    if series.is_empty() {
        return Err(NodeError::invalid(
            "series_1",
            "nothing to plot: connect a series",
        ));
    }
    let dim = |name: &str, v: i64| {
        u32::try_from(v)
            .ok()
            .filter(|v| (100..=8000).contains(v))
            .ok_or_else(|| NodeError::invalid(name, "must be between 100 and 8000 pixels"))
    };
    let plot = Plot {
        title: ctx.input("title")?,
        x_label: ctx.input("x_label")?,
        y_label: ctx.input("y_label")?,
        series,
        axes: ctx.choice("axes")?,
        size: (
            dim("width", ctx.input("width")?)?,
            dim("height", ctx.input("height")?)?,
        ),
        regions: ctx.input_opt("model")?,
    };
    let p: String = ctx.input("path")?;
    let path = ctx.output_path("path", &p)?;
    let format = PlotFormat::from_path(&path)
        .ok_or_else(|| NodeError::invalid("path", format!("'{p}' should end in .png or .svg")))?;
    let bytes =
        render_plot(&plot, format).map_err(|e| NodeError::invalid(e.socket(), e.to_string()))?;
    ctx.write_file(&path, &bytes)
}

/// Registers `plot`.
pub fn register(r: &mut Registry) {
    r.add("plot", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plot(axes: Axes) -> Plot {
        Plot {
            title: "a circle".into(),
            x_label: "x".into(),
            y_label: "y".into(),
            series: vec![
                PlotSeries {
                    label: "curve".into(),
                    points: (0..=64)
                        .map(|k| {
                            let a = k as f64 / 64.0 * std::f64::consts::TAU;
                            [3.0 * a.cos(), a.sin()]
                        })
                        .collect(),
                    style: Style::Line,
                    classes: None,
                },
                PlotSeries {
                    label: "points".into(),
                    points: vec![[0.0, 0.0], [1.0, 0.5]],
                    style: Style::Markers,
                    classes: None,
                },
            ],
            axes,
            size: (400, 300),
            regions: None,
        }
    }

    #[test]
    fn decision_regions_come_in_runs_of_one_class() {
        // logits (x, -x): class 0 where x > 0, class 1 where x < 0.
        let m = Model {
            kind: "mlp".into(),
            activation: "relu".into(),
            layers: vec![DenseLayer {
                inputs: 2,
                outputs: 2,
                weights: vec![1.0, 0.0, -1.0, 0.0],
                bias: vec![0.0, 0.0],
            }],
            features: vec!["a".into(), "b".into()],
            label: "c".into(),
            classes: vec![0, 1],
            mean: vec![0.0, 0.0],
            scale: vec![1.0, 1.0],
        };
        let runs = region_runs(&m, (-1.0, 1.0), (0.0, 1.0), 4, 2).unwrap();
        assert_eq!(runs.len(), 4);
        assert_eq!(runs[0], (1, (-1.0, 0.0), (0.0, 0.5)));
        assert_eq!(runs[1], (0, (0.0, 0.0), (1.0, 0.5)));
        let mut p = plot(Axes::Free);
        p.series[1].classes = Some(vec![0, 1]);
        p.regions = Some(Arc::new(m.clone()));
        let svg = String::from_utf8(render_plot(&p, PlotFormat::Svg).unwrap()).unwrap();
        assert!(svg.contains("points 1"), "one legend entry per class");
        let three = Model {
            features: vec!["a".into(), "b".into(), "c".into()],
            ..m
        };
        assert!(region_runs(&three, (0.0, 1.0), (0.0, 1.0), 2, 2).is_err());
    }

    #[test]
    fn equal_axes_have_equal_units() {
        let (x, y) = equalize((0.0, 6.0), (0.0, 1.0), (300, 200));
        assert!(((x.1 - x.0) / 300.0 - (y.1 - y.0) / 200.0).abs() < 1e-12);
        assert_eq!(x, (0.0, 6.0));
        assert!((y.0 + y.1 - 1.0).abs() < 1e-12, "centred: {y:?}");
    }

    #[test]
    fn draws_svg_with_labels_and_png_of_the_size() {
        let svg =
            String::from_utf8(render_plot(&plot(Axes::Equal), PlotFormat::Svg).unwrap()).unwrap();
        assert!(svg.contains("<svg") && svg.contains("a circle") && svg.contains("points"));
        let png = render_plot(&plot(Axes::Free), PlotFormat::Png).unwrap();
        let img = image::load_from_memory(&png).unwrap();
        assert_eq!((img.width(), img.height()), (400, 300));
        // Something other than white was drawn (the curve's blue is (31, 119, 180)).
        let rgb = img.to_rgb8();
        assert!(rgb.pixels().any(|p| p.0 == [31, 119, 180]));
    }
}
