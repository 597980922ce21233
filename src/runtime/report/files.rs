//! The report's view of written files: a node's files grouped by extension; a group of
//! several files is a frame sequence. Images become thumbnails (at most 256 x 256, EXR and HDR
//! tone-mapped) linking to the file, sequences an animated GIF; GIF and APNG animations are
//! shown as they are; SVG charts inline; CSV files as a table of their first rows; meshes as
//! a preview render (sequences animated, framed on the first frame).

use super::{esc, ReportError};
use cgnodes_api::registry::MeshHooks;
use cgnodes_api::types::Value;
use cgnodes_formats::animation::{self, AnimFormat, AnimOptions};
use image::RgbaImage;
use rayon::prelude::*;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;

/// The largest thumbnail side, in pixels.
pub const THUMB: u32 = 256;
/// The size a mesh sequence's frames are drawn at: half the thumbnail's, shown at the
/// thumbnail's size. A sequence redraws every frame, so this quarters the report's cost on a
/// frame range (the cloth of `bench/report_overhead.py`); a single mesh is drawn at full size.
pub const SEQUENCE_FRAME: (u32, u32) = (THUMB / 2, THUMB * 3 / 8);
/// Rows of a CSV file shown as a table.
pub const TABLE_ROWS: usize = 50;
/// At most this many frames of a sequence go into its animation (evenly spaced).
pub const MAX_ANIM_FRAMES: usize = 120;

/// Renders files into HTML, writing thumbnails under `dir/report_files/`.
pub struct FileRenderer {
    dir: PathBuf,
    files: PathBuf,
    /// The number of the last file made under `report_files/` (files are made in parallel).
    next: AtomicUsize,
    hooks: MeshHooks,
    /// Thumbnails drawn during the run: file -> (the file it is framed on, thumbnail).
    prefetched: Prefetched,
}

/// Mesh thumbnails drawn while the frames ran, by file: the file whose bounds framed it, and
/// the thumbnail.
pub type Prefetched = HashMap<PathBuf, (PathBuf, RgbaImage)>;

impl FileRenderer {
    /// A renderer for a report in `dir` (creates `dir/report_files/`).
    /// Meshes are drawn through `hooks` (linked only, when the hook is missing).
    pub fn new(
        dir: &Path,
        hooks: MeshHooks,
        prefetched: Prefetched,
    ) -> Result<FileRenderer, ReportError> {
        let files = dir.join("report_files");
        std::fs::create_dir_all(&files).map_err(|source| ReportError::Write {
            path: files.clone(),
            source,
        })?;
        Ok(FileRenderer {
            dir: dir.to_path_buf(),
            files,
            next: AtomicUsize::new(0),
            hooks,
            prefetched,
        })
    }

    /// A path as a relative URL from the report (an absolute `file://` one outside `dir`).
    fn href(&self, p: &Path) -> String {
        let s = match p.strip_prefix(&self.dir) {
            Ok(r) => r.to_string_lossy().replace('\\', "/"),
            Err(_) => format!(
                "file://{}",
                std::path::absolute(p).unwrap_or(p.to_path_buf()).display()
            ),
        };
        esc(&s
            .replace('%', "%25")
            .replace(' ', "%20")
            .replace('#', "%23")
            .replace('?', "%3F"))
    }

    /// A new file under `report_files/`: (path, href).
    fn new_file(&self, ext: &str) -> (PathBuf, String) {
        let n = self.next.fetch_add(1, Ordering::Relaxed) + 1;
        let name = format!("f{n:04}.{ext}");
        (self.files.join(&name), format!("report_files/{name}"))
    }

    /// HTML for the files one node wrote; `values` holds what some of them were written
    /// from (drawn from memory instead of read back).
    pub fn render(&self, written: &[PathBuf], values: &HashMap<PathBuf, Value>) -> String {
        let mut groups: Vec<(String, Vec<PathBuf>)> = Vec::new();
        for p in written {
            let ext = ext_of(p);
            match groups.iter_mut().find(|(e, _)| *e == ext) {
                Some((_, v)) => v.push(p.clone()),
                None => groups.push((ext, vec![p.clone()])),
            }
        }
        let mut out = String::from("<div class=\"files\">\n");
        let mut links = Vec::new();
        for (ext, mut paths) in groups {
            paths.sort();
            let html = match ext.as_str() {
                "gif" => Ok(self.anim_fig(&paths)),
                "png" if paths.len() == 1 && is_apng(&paths[0]) => Ok(self.anim_fig(&paths)),
                "png" | "jpg" | "jpeg" | "bmp" | "exr" | "hdr" => self.images(&paths, values),
                "svg" => Ok(self.svg(&paths)),
                "csv" => Ok(self.csv(&paths)),
                "obj" | "ply" | "usda" | "usd" | "off" => self.meshes(&paths, values),
                _ => {
                    links.extend(paths);
                    continue;
                }
            };
            out.push_str(&html.unwrap_or_else(|e| {
                format!(
                    "<figure><figcaption class=\"err\">{} file(s) *.{}: {}</figcaption></figure>\n",
                    paths.len(),
                    esc(&ext),
                    esc(&e.to_string())
                )
            }));
        }
        out.push_str("</div>\n");
        if !links.is_empty() {
            out.push_str("<p class=\"muted\">Also: ");
            let l: Vec<String> = links
                .iter()
                .map(|p| format!("<a href=\"{}\">{}</a>", self.href(p), esc(&name_of(p))))
                .collect();
            out.push_str(&l.join(", "));
            out.push_str("</p>\n");
        }
        out
    }

    /// A figure linking to the first of `paths`, captioned with the count.
    fn figure(&self, img_href: &str, (w, h): (u32, u32), paths: &[PathBuf]) -> String {
        let cap = match paths {
            [one] => esc(&name_of(one)),
            [first, .., last] => format!(
                "{} frames: {} … {}",
                paths.len(),
                esc(&name_of(first)),
                esc(&name_of(last))
            ),
            [] => String::new(),
        };
        format!(
            "<figure><a href=\"{}\"><img src=\"{img_href}\" width=\"{w}\" height=\"{h}\" alt=\"{cap}\"></a><figcaption>{cap}</figcaption></figure>\n",
            self.href(&paths[0])
        )
    }

    /// An animation written by the graph, shown as it is (scaled to the thumbnail box).
    fn anim_fig(&self, paths: &[PathBuf]) -> String {
        let mut s = String::new();
        for p in paths {
            let dims = image::image_dimensions(p).unwrap_or((THUMB, THUMB));
            let href = self.href(p);
            s.push_str(&self.figure(&href, fit(dims), std::slice::from_ref(p)));
        }
        s
    }

    fn images(
        &self,
        paths: &[PathBuf],
        values: &HashMap<PathBuf, Value>,
    ) -> Result<String, ReportError> {
        // The image a file was written from, encoded as the file is (tone-mapped when the
        // file is EXR or HDR); else the file read back.
        let read = |p: &PathBuf| match values.get(p) {
            Some(Value::Image(img)) if matches!(ext_of(p).as_str(), "exr" | "hdr") => {
                Ok(animation::tone_map(img))
            }
            Some(Value::Image(img)) => Ok(animation::to_rgba8(img)),
            _ => animation::read_rgba8(p).map_err(|e| ReportError::Image(e.to_string())),
        };
        if let [one] = paths {
            let t = thumbnail(&read(one)?);
            let (file, href) = self.new_file("png");
            save_png(&t, &file)?;
            return Ok(self.figure(&href, t.dimensions(), paths));
        }
        let picked = sample(paths);
        let frames = picked
            .par_iter()
            .map(|p| read(p).map(|i| thumbnail(&i)))
            .collect::<Result<Vec<_>, _>>()?;
        self.animation(&frames, paths)
    }

    /// Writes `frames` as an APNG under report_files/ and returns its figure. APNG, not GIF:
    /// no palette to quantize per frame (NeuQuant made the report of an 8-frame cloth run
    /// cost more than the run), lossless, and shown by every current browser.
    fn animation(&self, frames: &[RgbaImage], paths: &[PathBuf]) -> Result<String, ReportError> {
        self.animation_at(frames, paths, frames[0].dimensions())
    }

    /// `animation`, shown at `shown` pixels (frames drawn smaller are scaled by the browser).
    fn animation_at(
        &self,
        frames: &[RgbaImage],
        paths: &[PathBuf],
        shown: (u32, u32),
    ) -> Result<String, ReportError> {
        let opts = AnimOptions {
            format: AnimFormat::Apng,
            fps: 12.0,
            looped: true,
            max_width: 0,
            fast: true,
        };
        let bytes = animation::encode_animation(frames, &opts)
            .map_err(|e| ReportError::Image(e.to_string()))?;
        let (file, href) = self.new_file("png");
        cgnodes_api::io::write_atomic(&file, |w| w.write_all(&bytes))
            .map_err(|source| ReportError::Write { path: file, source })?;
        Ok(self.figure(&href, shown, paths))
    }

    fn svg(&self, paths: &[PathBuf]) -> String {
        let Some(last) = paths.last() else {
            return String::new();
        };
        let text = std::fs::read_to_string(last).unwrap_or_default();
        let start = text.find("<svg");
        match start {
            Some(i) if text.len() < 4 << 20 => format!(
                "<figure class=\"inline\">{}<figcaption><a href=\"{}\">{}</a>{}</figcaption></figure>\n",
                &text[i..],
                self.href(last),
                esc(&name_of(last)),
                more_files(paths.len())
            ),
            _ => format!(
                "<figure><a href=\"{}\">{}</a></figure>\n",
                self.href(last),
                esc(&name_of(last))
            ),
        }
    }

    fn csv(&self, paths: &[PathBuf]) -> String {
        let Some(last) = paths.last() else {
            return String::new();
        };
        let text = std::fs::read_to_string(last).unwrap_or_default();
        let mut rd = csv::ReaderBuilder::new()
            .has_headers(false)
            .flexible(true)
            .comment(Some(b'#'))
            .from_reader(text.as_bytes());
        let mut rows = Vec::new();
        let mut total = 0usize;
        for r in rd.records().flatten() {
            if rows.len() <= TABLE_ROWS {
                rows.push(r.iter().map(str::to_string).collect::<Vec<_>>());
            }
            total += 1;
        }
        let mut s = format!(
            "<figure><figcaption><a href=\"{}\">{}</a>{}</figcaption><div class=\"scroll\"><table>\n",
            self.href(last),
            esc(&name_of(last)),
            more_files(paths.len())
        );
        for (i, r) in rows.iter().enumerate() {
            let tag = if i == 0 { "th" } else { "td" };
            s.push_str("<tr>");
            for c in r {
                let c = if i == 0 { c.clone() } else { short_number(c) };
                s.push_str(&format!("<{tag}>{}</{tag}>", esc(&c)));
            }
            s.push_str("</tr>\n");
        }
        s.push_str("</table></div>");
        let data_rows = total.saturating_sub(1);
        if data_rows > TABLE_ROWS {
            s.push_str(&format!(
                "<p class=\"muted\">first {TABLE_ROWS} of {data_rows} rows; {} more in the file</p>",
                data_rows - TABLE_ROWS
            ));
        }
        s.push_str("</figure>\n");
        s
    }

    fn meshes(
        &self,
        paths: &[PathBuf],
        values: &HashMap<PathBuf, Value>,
    ) -> Result<String, ReportError> {
        let picked = sample(paths);
        let load = |p: &PathBuf| {
            if let Some(Value::Mesh(m)) = values.get(p) {
                return Ok(m.clone());
            }
            cgnodes_formats::mesh_file::load_mesh(p, &Default::default())
                .map(Arc::new)
                .map_err(|e| ReportError::Mesh(e.to_string()))
        };
        let first = load(picked[0])?;
        if first.num_faces() == 0 {
            return Ok(format!(
                "<figure><a href=\"{}\">{}</a><figcaption>{} points, no faces{}</figcaption></figure>\n",
                self.href(&paths[0]),
                esc(&name_of(&paths[0])),
                first.num_vertices(),
                more_files(paths.len())
            ));
        }
        let preview = self.hooks.preview.ok_or(ReportError::NoPreview)?;
        // Thumbnails drawn while the frames ran (`Prefetch`) are used when framed on the
        // same first file; the rest are drawn now, in parallel.
        let framed_on = picked[0];
        let (w, h) = if paths.len() > 1 {
            SEQUENCE_FRAME
        } else {
            (THUMB, THUMB * 3 / 4)
        };
        let frames = picked
            .par_iter()
            .map(|p| match self.prefetched.get(*p) {
                Some((on, img)) if on == framed_on && img.dimensions() == (w, h) => Ok(img.clone()),
                _ => {
                    let m = if *p == framed_on {
                        first.clone()
                    } else {
                        load(p)?
                    };
                    let img = preview(&first, &m, w, h).map_err(ReportError::Image)?;
                    Ok(animation::to_rgba8(&img))
                }
            })
            .collect::<Result<Vec<RgbaImage>, ReportError>>()?;
        if paths.len() == 1 {
            let t = &frames[0];
            let (file, href) = self.new_file("png");
            save_png(t, &file)?;
            return Ok(self.figure(&href, t.dimensions(), paths));
        }
        self.animation_at(&frames, paths, (THUMB, THUMB * 3 / 4))
    }
}

/// Lower-case extension of a path.
pub(super) fn ext_of(p: &Path) -> String {
    p.extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase()
}

fn name_of(p: &Path) -> String {
    p.file_name()
        .map(|n| n.to_string_lossy().to_string())
        .unwrap_or_default()
}

fn more_files(n: usize) -> String {
    if n > 1 {
        format!(" (the last of {n} files)")
    } else {
        String::new()
    }
}

/// Whether a PNG file is animated.
fn is_apng(p: &Path) -> bool {
    std::fs::File::open(p)
        .ok()
        .and_then(|f| image::codecs::png::PngDecoder::new(std::io::BufReader::new(f)).ok())
        .is_some_and(|d| d.is_apng().unwrap_or(false))
}

/// Size `dims` scaled down (never up) to fit a `THUMB` x `THUMB` box.
pub fn fit((w, h): (u32, u32)) -> (u32, u32) {
    let s = (THUMB as f64 / w.max(1) as f64)
        .min(THUMB as f64 / h.max(1) as f64)
        .min(1.0);
    (
        ((w as f64 * s).round() as u32).max(1),
        ((h as f64 * s).round() as u32).max(1),
    )
}

/// `img` downscaled to fit the thumbnail box (triangle filter).
pub fn thumbnail(img: &RgbaImage) -> RgbaImage {
    let (w, h) = fit(img.dimensions());
    if (w, h) == img.dimensions() {
        return img.clone();
    }
    image::imageops::resize(img, w, h, image::imageops::FilterType::Triangle)
}

fn save_png(img: &RgbaImage, path: &Path) -> Result<(), ReportError> {
    let bytes = cgnodes_formats::png::encode_png_fast(img.width(), img.height(), img.as_raw())
        .map_err(|e| ReportError::Image(e.to_string()))?;
    cgnodes_api::io::write_atomic(path, |w| w.write_all(&bytes)).map_err(|source| {
        ReportError::Write {
            path: path.to_path_buf(),
            source,
        }
    })
}

/// At most `MAX_ANIM_FRAMES` of `paths`, evenly spaced, the first and last included.
fn sample(paths: &[PathBuf]) -> Vec<&PathBuf> {
    let n = paths.len();
    if n <= MAX_ANIM_FRAMES {
        return paths.iter().collect();
    }
    (0..MAX_ANIM_FRAMES)
        .map(|i| &paths[i * (n - 1) / (MAX_ANIM_FRAMES - 1)])
        .collect()
}

/// A table cell for reading: a number with more than 7 significant digits shown with 7 (the
/// file keeps them all); anything else as it is.
fn short_number(cell: &str) -> String {
    let digits = cell.chars().filter(char::is_ascii_digit).count();
    match cell.trim().parse::<f64>() {
        Ok(x) if x.is_finite() && digits > 7 && x != 0.0 => {
            let mag = x.abs().log10().floor() as i32;
            if (-4..7).contains(&mag) {
                let decimals = (6 - mag).max(0) as usize;
                let t = format!("{x:.decimals$}");
                if t.contains('.') {
                    t.trim_end_matches('0').trim_end_matches('.').to_string()
                } else {
                    t
                }
            } else {
                format!("{x:.6e}")
            }
        }
        _ => cell.to_string(),
    }
}

#[cfg(test)]
mod short_number_tests {
    use super::short_number;

    #[test]
    fn long_numbers_keep_seven_significant_digits() {
        assert_eq!(short_number("0.20325000000000001"), "0.20325");
        assert_eq!(short_number("-1.8835174242825963"), "-1.883517");
        assert_eq!(short_number("0.014443706174223275"), "0.01444371");
        assert_eq!(short_number("1234.5678912"), "1234.568");
        assert_eq!(short_number("1.2345678912e-9"), "1.234568e-9");
        assert_eq!(short_number("801"), "801");
        assert_eq!(short_number("ok"), "ok");
    }
}
