use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// An image: linear RGBA in f32, rows top to bottom.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width * height` pixels, row-major from the top-left corner.
    pub pixels: Vec<[f32; 4]>,
}

impl Image {
    /// An image filled with one colour.
    pub fn new(width: u32, height: u32, fill: [f32; 4]) -> Image {
        Image {
            width,
            height,
            pixels: vec![fill; width as usize * height as usize],
        }
    }

    /// The pixel at column `x`, row `y` (row 0 at the top).
    pub fn get(&self, x: u32, y: u32) -> [f32; 4] {
        self.pixels[y as usize * self.width as usize + x as usize]
    }

    /// Sets the pixel at column `x`, row `y`.
    pub fn set(&mut self, x: u32, y: u32, c: [f32; 4]) {
        let w = self.width as usize;
        self.pixels[y as usize * w + x as usize] = c;
    }
}

/// Particles with named per-particle attributes (velocity, density, ...).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Points {
    /// 2 or 3: the dimension of the simulation (2-D points keep z = 0).
    pub dim: u8,
    /// Particle positions.
    pub positions: Vec<[f64; 3]>,
    /// Scalar attributes, one value per particle.
    pub scalars: BTreeMap<String, Vec<f64>>,
    /// Vector attributes, one value per particle.
    pub vectors: BTreeMap<String, Vec<[f64; 3]>>,
}

/// Named numeric columns of equal length, for metrics and logs. `meta` carries short text
/// facts such as why an iteration stopped.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Table {
    /// Columns in order.
    pub columns: Vec<(String, Vec<f64>)>,
    /// Text facts (for example `stop_reason`).
    pub meta: BTreeMap<String, String>,
}

impl Table {
    /// An empty table with these column names.
    pub fn with_columns(names: &[&str]) -> Table {
        Table {
            columns: names.iter().map(|n| (n.to_string(), Vec::new())).collect(),
            meta: BTreeMap::new(),
        }
    }

    /// A one-row table from name/value pairs.
    pub fn from_row(row: &[(&str, f64)]) -> Table {
        Table {
            columns: row.iter().map(|(n, v)| (n.to_string(), vec![*v])).collect(),
            meta: BTreeMap::new(),
        }
    }

    /// Appends a row; `values` follow the column order.
    pub fn push_row(&mut self, values: &[f64]) {
        for ((_, col), v) in self.columns.iter_mut().zip(values) {
            col.push(*v);
        }
    }

    /// The column called `name`.
    pub fn column(&self, name: &str) -> Option<&[f64]> {
        self.columns
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, c)| c.as_slice())
    }

    /// Adds or replaces a column.
    pub fn set_column(&mut self, name: &str, values: Vec<f64>) {
        match self.columns.iter_mut().find(|(n, _)| n == name) {
            Some((_, c)) => *c = values,
            None => self.columns.push((name.to_string(), values)),
        }
    }

    /// Number of rows (the longest column).
    pub fn num_rows(&self) -> usize {
        self.columns.iter().map(|(_, c)| c.len()).max().unwrap_or(0)
    }

    /// CSV text with a header row (RFC 4180 quoting); a shorter column leaves its cells
    /// empty.
    pub fn to_csv(&self) -> String {
        let header: Vec<String> = self.columns.iter().map(|(n, _)| n.clone()).collect();
        let rows = (0..self.num_rows()).map(|r| {
            self.columns
                .iter()
                .map(|(_, c)| c.get(r).map(|v| format!("{v}")).unwrap_or_default())
                .collect::<Vec<String>>()
        });
        crate::io::csv::to_text(std::iter::once(header).chain(rows))
    }
}

/// A polyline or sampled curve (points in order).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Curve {
    /// Points along the curve.
    pub points: Vec<[f64; 3]>,
    /// Whether the last point joins the first.
    pub closed: bool,
}
