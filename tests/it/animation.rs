//! `frames_to_video` and `mesh_sequence`: animations assembled from the frames written so
//! far, also when each frame runs in its own process (only the files of earlier frames are
//! there), decoding back to the right frames.

use crate::common::run_graph;
use cgnodes::nodes::builtin_registry;
use cgnodes::nodes::image::animation::downscale;
use image::{AnimationDecoder, RgbaImage};
use std::path::Path;

fn open(p: &Path) -> std::io::BufReader<std::fs::File> {
    std::io::BufReader::new(std::fs::File::open(p).unwrap())
}

fn frames_of<'a>(d: impl AnimationDecoder<'a>) -> Vec<RgbaImage> {
    d.into_frames()
        .collect_frames()
        .unwrap()
        .into_iter()
        .map(|f| f.into_buffer())
        .collect()
}

fn decode_gif(p: &Path) -> Vec<RgbaImage> {
    frames_of(image::codecs::gif::GifDecoder::new(open(p)).unwrap())
}

fn decode_apng(p: &Path) -> Vec<RgbaImage> {
    frames_of(
        image::codecs::png::PngDecoder::new(open(p))
            .unwrap()
            .apng()
            .unwrap(),
    )
}

/// Frame `k` of a test sequence: a gradient with few colours (a GIF keeps them exactly).
fn frame(k: u32) -> RgbaImage {
    RgbaImage::from_fn(12, 8, |x, y| {
        image::Rgba([(x * 20) as u8, (y * 30) as u8, (k * 70) as u8, 255])
    })
}

#[test]
fn frames_to_video_collects_the_files_of_earlier_processes() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    std::fs::create_dir_all(out.join("frames")).unwrap();
    // Frames 1..3 were written by earlier processes; frame 7 is stale (after the current one).
    for k in [1, 2, 3, 7] {
        frame(k)
            .save(out.join(format!("frames/f_{k:03}.png")))
            .unwrap();
    }
    let graph = r#"{"format": "cgnodes-graph", "version": 1, "nodes": {
        "gif": {"type": "frames_to_video", "params": {"frames": "frames/f_{frame:03}.png", "path": "a.gif"}},
        "apng": {"type": "frames_to_video", "params": {"frames": "frames/f_{frame:03}.png", "path": "a.png",
                 "format": "apng", "max_width": 6, "loop": false}}}}"#;
    // This process runs frame 3 only, as `cgnodes run --frames 3..3` would.
    let r = run_graph(graph, &builtin_registry(), dir.path(), &out, 1, 3..=3);
    assert!(r[0].errors().is_empty(), "{:?}", r[0].errors());
    let gif = decode_gif(&out.join("a.gif"));
    assert_eq!(gif.len(), 3);
    for (k, f) in (1..=3).zip(&gif) {
        assert_eq!(*f, frame(k));
    }
    let apng = decode_apng(&out.join("a.png"));
    assert_eq!(apng.len(), 3);
    assert_eq!(apng[0], downscale(&frame(1), 6));
    assert_eq!(apng[0].dimensions(), (6, 4));
    // A pattern that matches nothing is an error naming the socket.
    let none = r#"{"format": "cgnodes-graph", "version": 1, "nodes": {
        "v": {"type": "frames_to_video", "params": {"frames": "nope/f_{frame}.png", "path": "b.gif"}}}}"#;
    let r = run_graph(none, &builtin_registry(), dir.path(), &out, 1, 0..=0);
    let e = r[0].errors().join("\n");
    assert!(e.contains("frames") && e.contains("no file matches"), "{e}");
}

#[test]
fn mesh_sequence_renders_every_frame_with_one_framing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let graph = r#"{"format": "cgnodes-graph", "version": 1, "nodes": {
        "grid": {"type": "mesh_grid", "params": {"cells_u": 3, "cells_v": 3}},
        "seq": {"type": "mesh_sequence", "inputs": {"mesh": "grid.mesh"},
                "params": {"path": "anim/grid.gif", "width": 64, "height": 48}}}}"#;
    let r = run_graph(graph, &builtin_registry(), dir.path(), &out, 1, 1..=3);
    for f in &r {
        assert!(f.errors().is_empty(), "{:?}", f.errors());
    }
    let frames = decode_gif(&out.join("anim/grid.gif"));
    assert_eq!(frames.len(), 3);
    // The previews are kept beside the animation with the first frame's framing.
    assert!(out.join("anim/grid_frames/0003.png").is_file());
    assert!(out.join("anim/grid_frames/framing.json").is_file());
    // A static mesh gives identical frames that show the mesh (not only background).
    let bg = *frames[0].get_pixel(0, 0);
    let covered = frames[0].pixels().filter(|p| **p != bg).count();
    assert!(covered > 64 * 48 / 8, "{covered}");
    assert_eq!(frames[0], frames[2]);
}
