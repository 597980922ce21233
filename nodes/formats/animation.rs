//! Animations of frame sequences: animated GIF (`image`'s GIF encoder: a frame's own colours
//! when it has at most 256, else a NeuQuant palette per frame, Dekker 1994) and APNG (the `png`
//! crate), from 8-bit sRGB frames. Frames written by earlier frames of a run, or by other
//! processes run once per frame, are collected from a `{frame}` path pattern
//! (`FramePattern`). Shared by `frames_to_video`, `mesh_sequence` and the run report.

use super::srgb::linear_to_srgb;
use cgnodes_api::node::substitute_frame;
use cgnodes_api::prelude::*;
use image::RgbaImage;
use std::path::{Path, PathBuf};

/// The animation file format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AnimFormat {
    /// Animated GIF: 256 colours per frame, 1-bit transparency, delays in 1/100 s.
    Gif,
    /// Animated PNG: full 8-bit RGBA, lossless.
    Apng,
}

impl Choice for AnimFormat {
    const CHOICES: &'static [(&'static str, Self)] =
        &[("gif", AnimFormat::Gif), ("apng", AnimFormat::Apng)];
}

/// How frames become an animation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AnimOptions {
    /// GIF or APNG.
    pub format: AnimFormat,
    /// Frames per second (0.1 to 100).
    pub fps: f64,
    /// Loop forever (else play once).
    pub looped: bool,
    /// Downscale frames wider than this (keeping the aspect ratio); 0 keeps the size.
    pub max_width: u32,
    /// APNG: compress fast (fdeflate) rather than small; for previews made on every run.
    pub fast: bool,
}

impl Default for AnimOptions {
    fn default() -> Self {
        AnimOptions {
            format: AnimFormat::Gif,
            fps: 12.0,
            looped: true,
            max_width: 0,
            fast: false,
        }
    }
}

/// An image as 8-bit sRGB RGBA, exactly as `image_save` writes a PNG with its defaults
/// (sRGB curve, no exposure; alpha linear).
pub fn to_rgba8(img: &Image) -> RgbaImage {
    let enc = |v: f32| (linear_to_srgb(v) * 255.0 + 0.5).clamp(0.0, 255.0) as u8;
    let a8 = |v: f32| {
        let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
        (v * 255.0 + 0.5) as u8
    };
    let data: Vec<u8> = img
        .pixels
        .iter()
        .flat_map(|p| [enc(p[0]), enc(p[1]), enc(p[2]), a8(p[3])])
        .collect();
    RgbaImage::from_raw(img.width, img.height, data).unwrap_or_default()
}

/// A linear HDR image tone-mapped to 8-bit sRGB: with the largest finite channel value
/// `w` above 1, each channel goes through extended Reinhard `c (1 + c / w^2) / (1 + c)`
/// (Reinhard et al. 2002, eq. 4), which maps `w` to 1; images within 0..1 are only clamped.
pub fn tone_map(img: &Image) -> RgbaImage {
    let w = img
        .pixels
        .iter()
        .flat_map(|p| p[..3].iter().copied())
        .filter(|v| v.is_finite())
        .fold(0.0f32, f32::max);
    if w <= 1.0 {
        return to_rgba8(img);
    }
    let tm = |c: f32| {
        let c = if c.is_finite() { c.max(0.0) } else { 0.0 };
        c * (1.0 + c / (w * w)) / (1.0 + c)
    };
    let mapped = Image {
        width: img.width,
        height: img.height,
        pixels: img
            .pixels
            .iter()
            .map(|p| [tm(p[0]), tm(p[1]), tm(p[2]), p[3]])
            .collect(),
    };
    to_rgba8(&mapped)
}

/// Reads an image file as 8-bit sRGB: 8- and 16-bit files keep their stored code values
/// (16-bit rounded), EXR and HDR (linear) are tone-mapped with `tone_map`.
pub fn read_rgba8(path: &Path) -> Result<RgbaImage, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    if ext == "exr" || ext == "hdr" {
        let img = crate::image_file::decode_image(&bytes, crate::image_file::ColorSpace::Raw)
            .map_err(|e| format!("{}: {e}", path.display()))?;
        return Ok(tone_map(&img));
    }
    super::file_check::check_complete(&bytes).map_err(|e| format!("{}: {e}", path.display()))?;
    image::load_from_memory(&bytes)
        .map(|d| d.to_rgba8())
        .map_err(|e| format!("{}: {e}", path.display()))
}

/// `img` downscaled to at most `max_width` pixels wide (triangle filter, aspect kept,
/// height rounded); unchanged when it is not wider or `max_width` is 0.
pub fn downscale(img: &RgbaImage, max_width: u32) -> RgbaImage {
    let (w, h) = img.dimensions();
    if max_width == 0 || w <= max_width {
        return img.clone();
    }
    let nh = ((h as f64 * max_width as f64 / w as f64).round() as u32).max(1);
    image::imageops::resize(img, max_width, nh, image::imageops::FilterType::Triangle)
}

/// One frame made ready for an animation: its size before downscaling, and for APNG the
/// downscaled pixels or for GIF the frame quantized and LZW-compressed, so that assembling an
/// animation again with one more frame only copies bytes.
#[derive(Clone, Debug)]
pub struct Prepared {
    /// Width and height of the source image (before downscaling).
    pub source_size: (u32, u32),
    /// Width and height in the animation.
    pub size: (u32, u32),
    data: PreparedData,
}

#[derive(Clone, Debug)]
enum PreparedData {
    Rgba(RgbaImage),
    Gif(gif::Frame<'static>),
}

impl Prepared {
    /// Bytes held (for the memo's bound).
    fn bytes(&self) -> usize {
        match &self.data {
            PreparedData::Rgba(r) => r.as_raw().len(),
            PreparedData::Gif(g) => g.buffer.len() + 768,
        }
    }
}

/// Downscales `img` per `opts.max_width` and, for GIF, quantizes it (a frame's own colours
/// when it has at most 256, else NeuQuant at speed 10) and LZW-compresses it.
pub fn prepare(img: &RgbaImage, opts: &AnimOptions) -> Result<Prepared, String> {
    let small = downscale(img, opts.max_width);
    let (w, h) = small.dimensions();
    if w > u16::MAX as u32 || h > u16::MAX as u32 || w == 0 || h == 0 {
        return Err(format!("{w}x{h} frames cannot be animated"));
    }
    let data = match opts.format {
        AnimFormat::Apng => PreparedData::Rgba(small),
        AnimFormat::Gif => {
            let mut px = small.into_raw();
            let mut f = gif::Frame::from_rgba_speed(w as u16, h as u16, &mut px, 10);
            f.dispose = gif::DisposalMethod::Background;
            f.make_lzw_pre_encoded();
            PreparedData::Gif(f)
        }
    };
    Ok(Prepared {
        source_size: img.dimensions(),
        size: (w, h),
        data,
    })
}

type MemoKey = (PathBuf, u64, std::time::SystemTime, u32, bool);
type Memo = Option<(usize, std::collections::HashMap<MemoKey, Arc<Prepared>>)>;

/// Prepared frames of files by (path, length, modification time, max width, GIF), so that a
/// run assembling the animation every frame reads and quantizes each file once. Cleared
/// when it holds more than 256 MiB.
static MEMO: std::sync::Mutex<Memo> = std::sync::Mutex::new(None);

/// `prepare` of an image file (read with `read_rgba8`), memoized per process.
pub fn prepare_file(path: &Path, opts: &AnimOptions) -> Result<Arc<Prepared>, String> {
    let meta = std::fs::metadata(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let key: MemoKey = (
        path.to_path_buf(),
        meta.len(),
        meta.modified().unwrap_or(std::time::UNIX_EPOCH),
        opts.max_width,
        opts.format == AnimFormat::Gif,
    );
    {
        let memo = MEMO.lock().unwrap_or_else(|p| p.into_inner());
        if let Some(p) = memo.as_ref().and_then(|(_, m)| m.get(&key)) {
            return Ok(p.clone());
        }
    }
    let p = Arc::new(prepare(&read_rgba8(path)?, opts)?);
    let mut memo = MEMO.lock().unwrap_or_else(|p| p.into_inner());
    let (bytes, map) = memo.get_or_insert_with(Default::default);
    if *bytes > 256 << 20 {
        map.clear();
        *bytes = 0;
    }
    *bytes += p.bytes();
    map.insert(key, p.clone());
    Ok(p)
}

/// Writes prepared frames (all of one size, all prepared with `opts`) as an animation.
pub fn encode_prepared(frames: &[Arc<Prepared>], opts: &AnimOptions) -> Result<Vec<u8>, String> {
    let first = frames.first().ok_or("no frames")?;
    if !(opts.fps.is_finite() && (0.1..=100.0).contains(&opts.fps)) {
        return Err(format!("fps {} is not within 0.1..100", opts.fps));
    }
    for (i, f) in frames.iter().enumerate() {
        if f.source_size != first.source_size || f.size != first.size {
            return Err(format!(
                "frame {} is {}x{} but the first is {}x{}",
                i + 1,
                f.source_size.0,
                f.source_size.1,
                first.source_size.0,
                first.source_size.1
            ));
        }
    }
    let (w, h) = first.size;
    let mut out = Vec::new();
    match opts.format {
        AnimFormat::Gif => {
            // 1/100 s is GIF's delay unit.
            let cs = ((100.0 / opts.fps).round() as u16).max(1);
            let e = |e: gif::EncodingError| e.to_string();
            let mut enc = gif::Encoder::new(&mut out, w as u16, h as u16, &[]).map_err(e)?;
            let rep = if opts.looped {
                gif::Repeat::Infinite
            } else {
                gif::Repeat::Finite(0)
            };
            enc.set_repeat(rep).map_err(e)?;
            for f in frames {
                let PreparedData::Gif(g) = &f.data else {
                    return Err("frame prepared for APNG, not GIF".into());
                };
                let mut g = g.clone();
                g.delay = cs;
                enc.write_lzw_pre_encoded_frame(&g).map_err(e)?;
            }
        }
        AnimFormat::Apng => {
            let mut enc = png::Encoder::new(&mut out, w, h);
            enc.set_color(png::ColorType::Rgba);
            enc.set_depth(png::BitDepth::Eight);
            if opts.fast {
                enc.set_compression(png::Compression::Fast);
            }
            let e = |e: png::EncodingError| e.to_string();
            enc.set_animated(frames.len() as u32, if opts.looped { 0 } else { 1 })
                .map_err(e)?;
            // delay = num / den seconds; den <= 10,000 for fps <= 100.
            enc.set_frame_delay(100, (opts.fps * 100.0).round() as u16)
                .map_err(e)?;
            let mut wr = enc.write_header().map_err(e)?;
            for f in frames {
                let PreparedData::Rgba(r) = &f.data else {
                    return Err("frame prepared for GIF, not APNG".into());
                };
                wr.write_image_data(r.as_raw()).map_err(e)?;
            }
            wr.finish().map_err(e)?;
        }
    }
    Ok(out)
}

/// Encodes frames (all of one size) as an animation; frames are downscaled per
/// `opts.max_width` first.
pub fn encode_animation(frames: &[RgbaImage], opts: &AnimOptions) -> Result<Vec<u8>, String> {
    let prepared = frames
        .iter()
        .map(|f| prepare(f, opts).map(Arc::new))
        .collect::<Result<Vec<_>, _>>()?;
    encode_prepared(&prepared, opts)
}

/// A path pattern with one `{frame}` or `{frame:0N}` in its file name
/// (`images/dam_{frame:03}.png`): where the files of a frame sequence are.
#[derive(Clone, Debug, PartialEq)]
pub struct FramePattern {
    /// The folder part (no `{frame}` in it), possibly empty.
    pub dir: PathBuf,
    /// The file name with its `{frame...}`.
    pub name: String,
}

impl FramePattern {
    /// Parses a pattern: exactly one `{frame...}`, in the file name, that `substitute_frame`
    /// accepts.
    pub fn parse(pattern: &str) -> Result<FramePattern, String> {
        let p = Path::new(pattern);
        let name = p
            .file_name()
            .and_then(|n| n.to_str())
            .ok_or_else(|| format!("'{pattern}' has no file name"))?
            .to_string();
        let dir = p.parent().map(Path::to_path_buf).unwrap_or_default();
        if dir.to_string_lossy().contains("{frame") {
            return Err(format!(
                "'{pattern}': {{frame}} may only appear in the file name"
            ));
        }
        if name.matches("{frame").count() != 1 {
            return Err(format!(
                "'{pattern}' needs exactly one {{frame}} or {{frame:0N}} in its file name"
            ));
        }
        substitute_frame(&name, 0)?;
        Ok(FramePattern { dir, name })
    }

    /// The file name of `frame`.
    pub fn file_name(&self, frame: i64) -> String {
        substitute_frame(&self.name, frame).unwrap_or_default()
    }

    /// The frames whose files exist in `folder` (the pattern's folder, resolved), at most
    /// `upto`, in order, with their paths. A name counts only if the pattern gives exactly
    /// it for its number (`dam_7.png` is not frame 7 of `dam_{frame:03}.png`).
    pub fn existing(&self, folder: &Path, upto: i64) -> Vec<(i64, PathBuf)> {
        let i = self.name.find("{frame").unwrap_or(0);
        let j = self.name[i..].find('}').map(|k| i + k + 1).unwrap_or(i);
        let (pre, suf) = (&self.name[..i], &self.name[j..]);
        let Ok(rd) = std::fs::read_dir(folder) else {
            return Vec::new();
        };
        let mut out: Vec<(i64, PathBuf)> = rd
            .filter_map(|e| e.ok())
            .filter_map(|e| {
                let n = e.file_name().to_str()?.to_string();
                let mid = n.strip_prefix(pre)?.strip_suffix(suf)?;
                let f: i64 = mid.parse().ok()?;
                (f <= upto && self.file_name(f) == n && e.path().is_file()).then(|| (f, e.path()))
            })
            .collect();
        out.sort();
        out
    }
}

// The options and assembly `frames_to_video` and `mesh_sequence` share.

/// Declares the animation options `read_options` reads (`format`, `fps`, `loop`,
/// `max_width`), shared with `mesh_sequence`.
pub fn declare_options(b: &mut NodeBuilder) {
    b.add_choice::<AnimFormat>("format")
        .doc("gif (256 colours a frame) or apng (lossless).");
    let d = AnimOptions::default();
    b.add_input::<f64>("fps")
        .default(d.fps)
        .range(0.1, 100.0)
        .doc("Frames per second.");
    b.add_input::<bool>("loop")
        .default(d.looped)
        .doc("Loop forever (else play once).");
    b.add_input::<i64>("max_width")
        .default(d.max_width as i64)
        .range(0.0, 65535.0)
        .doc("Downscale wider frames to this width (aspect kept); 0 keeps the size.");
}

/// Reads the animation options of a node with `format`, `fps`, `loop` and `max_width`
/// sockets (`frames_to_video`, `mesh_sequence`), checking the path's extension.
pub fn read_options(ctx: &ExecContext, path: &str) -> Result<AnimOptions, NodeError> {
    let format: AnimFormat = ctx.choice("format")?;
    let fps: f64 = ctx.input("fps")?;
    if !(fps.is_finite() && (0.1..=100.0).contains(&fps)) {
        return Err(NodeError::invalid("fps", "must be within 0.1..100"));
    }
    let max_width: i64 = ctx.input("max_width")?;
    let max_width = u32::try_from(max_width)
        .ok()
        .filter(|w| *w <= 65535)
        .ok_or_else(|| NodeError::invalid("max_width", "must be within 0..65535"))?;
    let ext = std::path::Path::new(path)
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    let ok = match format {
        AnimFormat::Gif => ext == "gif",
        AnimFormat::Apng => ext == "png" || ext == "apng",
    };
    if !ok {
        let want = match format {
            AnimFormat::Gif => ".gif",
            AnimFormat::Apng => ".png or .apng",
        };
        return Err(NodeError::invalid(
            "path",
            format!("'{path}': format {format:?} writes {want} files"),
        ));
    }
    Ok(AnimOptions {
        format,
        fps,
        looped: ctx.input("loop")?,
        max_width,
        fast: false,
    })
}

/// The frames of `pattern` (relative to the output folder) up to the current frame, read as
/// 8-bit sRGB and prepared for `opts` (memoized per file), with `current` (this frame's
/// image, if given) in place of this frame's file, assembled into the animation's bytes.
/// `socket` names the pattern's socket for errors.
pub fn assemble(
    ctx: &ExecContext,
    socket: &str,
    pattern: &str,
    current: Option<RgbaImage>,
    opts: &AnimOptions,
) -> Result<Vec<u8>, NodeError> {
    let bad = |e: String| NodeError::invalid(socket, e);
    let pat = FramePattern::parse(pattern).map_err(bad)?;
    let folder = if pat.dir.as_os_str().is_empty() {
        ctx.files().out_dir.clone()
    } else {
        ctx.output_path(socket, &pat.dir.to_string_lossy())?
    };
    let frame = ctx.frame();
    let mut frames = Vec::new();
    for (f, p) in pat.existing(&folder, frame) {
        if f == frame && current.is_some() {
            continue;
        }
        frames.push(prepare_file(&p, opts).map_err(bad)?);
    }
    if let Some(c) = current {
        frames.push(Arc::new(prepare(&c, opts).map_err(bad)?));
    }
    if frames.is_empty() {
        return Err(bad(format!(
            "no file matches '{pattern}' under {} for frames up to {frame}",
            folder.display()
        )));
    }
    encode_prepared(&frames, opts).map_err(|e| {
        bad(format!(
            "'{pattern}': {e} (files of an earlier run at another size? remove them)"
        ))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(w: u32, h: u32, k: u8) -> RgbaImage {
        RgbaImage::from_fn(w, h, |x, y| {
            image::Rgba([(x * 40) as u8, (y * 50) as u8, k.wrapping_mul(60), 255])
        })
    }

    fn decode_frames(bytes: &[u8], format: AnimFormat) -> Vec<RgbaImage> {
        use image::AnimationDecoder;
        let cur = std::io::Cursor::new(bytes);
        let frames = match format {
            AnimFormat::Gif => image::codecs::gif::GifDecoder::new(cur)
                .unwrap()
                .into_frames()
                .collect_frames(),
            AnimFormat::Apng => image::codecs::png::PngDecoder::new(cur)
                .unwrap()
                .apng()
                .unwrap()
                .into_frames()
                .collect_frames(),
        };
        frames
            .unwrap()
            .into_iter()
            .map(|f| f.into_buffer())
            .collect()
    }

    #[test]
    fn gif_and_apng_decode_back_to_the_frames() {
        // Few colours per frame: the GIF keeps them exactly (no quantization).
        let frames: Vec<RgbaImage> = (0..3).map(|k| frame(6, 4, k)).collect();
        for format in [AnimFormat::Gif, AnimFormat::Apng] {
            let opts = AnimOptions {
                format,
                ..Default::default()
            };
            let bytes = encode_animation(&frames, &opts).unwrap();
            let back = decode_frames(&bytes, format);
            assert_eq!(back.len(), 3, "{format:?}");
            for (a, b) in frames.iter().zip(&back) {
                assert_eq!(a, b, "{format:?}");
            }
        }
    }

    #[test]
    fn downscaling_keeps_the_aspect_and_applies_to_every_frame() {
        let frames: Vec<RgbaImage> = (0..2).map(|k| frame(10, 5, k)).collect();
        let opts = AnimOptions {
            format: AnimFormat::Apng,
            max_width: 4,
            ..Default::default()
        };
        let back = decode_frames(&encode_animation(&frames, &opts).unwrap(), opts.format);
        assert_eq!(back[0].dimensions(), (4, 2));
        assert_eq!(back[1], downscale(&frames[1], 4));
        let mismatched = [frame(4, 4, 0), frame(5, 4, 0)];
        let e = encode_animation(&mismatched, &opts).unwrap_err();
        assert!(e.contains("frame 2 is 5x4"), "{e}");
        let slow = AnimOptions { fps: 0.0, ..opts };
        assert!(encode_animation(&mismatched[..1], &slow).is_err());
    }

    #[test]
    fn rgba8_matches_image_save_and_tone_map_keeps_ldr() {
        let mut img = Image::new(2, 1, [0.2, 0.5, 1.5, 1.0]);
        img.set(1, 0, [f32::NAN, 0.0, 0.01, 0.5]);
        let png = crate::image_file::encode_image(
            &img,
            crate::image_file::ImageFileFormat::Png,
            0.0,
            0.0,
        )
        .unwrap();
        let saved = image::load_from_memory(&png).unwrap().to_rgba8();
        assert_eq!(to_rgba8(&img), saved);
        let ldr = Image::new(1, 1, [0.25, 0.5, 1.0, 1.0]);
        assert_eq!(tone_map(&ldr), to_rgba8(&ldr));
        // Extended Reinhard maps the brightest value (4) to white and 1 to (1 + 1/16) / 2.
        let hdr = Image::new(1, 1, [4.0, 1.0, 0.0, 1.0]);
        let want = to_rgba8(&Image::new(1, 1, [1.0, 0.53125, 0.0, 1.0]));
        assert_eq!(tone_map(&hdr), want);
    }

    #[test]
    fn patterns_find_exactly_their_frames() {
        let dir = tempfile::tempdir().unwrap();
        for n in [
            "f_001.png",
            "f_003.png",
            "f_7.png",
            "f_010.png",
            "g_002.png",
            "f_abc.png",
        ] {
            std::fs::write(dir.path().join(n), b"x").unwrap();
        }
        let p = FramePattern::parse("sub/f_{frame:03}.png").unwrap();
        assert_eq!(p.dir, Path::new("sub"));
        let got: Vec<i64> = p.existing(dir.path(), 5).iter().map(|(f, _)| *f).collect();
        assert_eq!(got, vec![1, 3]);
        let all: Vec<i64> = p.existing(dir.path(), 99).iter().map(|(f, _)| *f).collect();
        assert_eq!(all, vec![1, 3, 10]);
        assert!(FramePattern::parse("f.png").is_err());
        assert!(FramePattern::parse("{frame}/f_{frame}.png").is_err());
        assert!(FramePattern::parse("f_{frame}_{frame}.png").is_err());
        assert!(FramePattern::parse("f_{frame:x}.png").is_err());
    }
}
