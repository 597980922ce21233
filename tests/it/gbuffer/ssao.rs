//! SSAO against references (1 on an open plane, darker in a corner with a larger radius)
//! and the camera recovered from a G-buffer.

use super::{gbuffer_of, lit_scene, obj, rmse};
use crate::common::run_node;
use cgnodes::nodes::mesh::mesh_plane::plane_mesh;
use cgnodes::nodes::render::gbuffer::ssao::{ssao, SsaoParams};
use cgnodes::nodes::render::gbuffer::{camera_from_gbuffer, is_surface};
use cgnodes::types::*;
use std::sync::Arc;

/// Camera straight down onto a large plane: every hemisphere sample is above the surface,
/// so nothing occludes (also with normals reconstructed from the positions).
#[test]
fn ssao_is_one_on_an_open_plane() {
    let cam = Camera {
        eye: [0.0, 3.0, 0.0],
        target: [0.0, 0.0, 0.0],
        up: [0.0, 0.0, -1.0],
        fov_deg: 50.0,
        width: 48,
        height: 40,
        ..Default::default()
    };
    let scene = Scene {
        objects: vec![obj(plane_mesh(40.0, [0.0; 3], 1, 1.0), None)],
        ..Default::default()
    };
    let out = gbuffer_of(&scene, &cam);
    for normal in [Some(&out.normal), None] {
        let ao = ssao(
            &out.position,
            normal,
            Some(&out.depth),
            &cam,
            &SsaoParams {
                radius: 0.8,
                ..Default::default()
            },
        );
        assert!(ao.pixels.iter().all(|p| p[0] == 1.0));
    }
}

/// Floor and back wall meeting at z = 0: floor pixels near the wall are occluded, more so
/// with a larger radius; floor pixels far from the wall stay open.
#[test]
fn ssao_darkens_a_corner_more_with_a_larger_radius() {
    let wall = Mesh::from_triangles(
        vec![
            [-3.0, 0.0, 0.0],
            [3.0, 0.0, 0.0],
            [3.0, 3.0, 0.0],
            [-3.0, 3.0, 0.0],
        ],
        &[[0, 1, 2], [0, 2, 3]],
    )
    .unwrap();
    let scene = Scene {
        objects: vec![
            obj(plane_mesh(6.0, [0.0, 0.0, 3.0], 1, 1.0), None),
            obj(wall, None),
        ],
        ..Default::default()
    };
    let cam = Camera {
        eye: [0.0, 1.2, 2.5],
        target: [0.0, 0.3, 0.0],
        fov_deg: 60.0,
        width: 64,
        height: 48,
        ..Default::default()
    };
    let out = gbuffer_of(&scene, &cam);
    let mean_where = |ao: &Image, near: bool| {
        let (mut s, mut n) = (0.0, 0);
        for (i, p) in out.position.pixels.iter().enumerate() {
            let on_floor = is_surface(*p) && p[1].abs() < 1e-4;
            let pick = if near {
                p[2] > 0.02 && p[2] < 0.2
            } else {
                p[2] > 1.2
            };
            if on_floor && pick {
                s += ao.pixels[i][0] as f64;
                n += 1;
            }
        }
        assert!(n > 10, "{n} pixels");
        s / n as f64
    };
    let mut last = 1.0;
    for r in [0.25, 0.5, 1.0] {
        let par = SsaoParams {
            radius: r,
            samples: 32,
            bias: 0.01,
            ..Default::default()
        };
        let ao = ssao(
            &out.position,
            Some(&out.normal),
            Some(&out.depth),
            &cam,
            &par,
        );
        let near = mean_where(&ao, true);
        println!("radius {r}: AO near the wall {near:.4}");
        assert!(near < last, "radius {r}: {near} after {last}");
        last = near;
        assert_eq!(mean_where(&ao, false), 1.0);
    }
    assert!(last < 0.95, "{last}");
}

/// The camera recovered from the position and depth passes is the one they were rendered
/// with, also when every depth is the same (a plane facing the camera), and the ssao node
/// without a camera gives the AO it gives with one.
#[test]
fn camera_is_recovered_from_position_and_depth() {
    let (scene, cam) = lit_scene();
    let out = gbuffer_of(&scene, &cam);
    let facing = Camera {
        eye: [0.3, 0.2, 5.0],
        target: [0.3, 0.2, 0.0],
        up: [0.2, 1.0, 0.0],
        fov_deg: 30.0,
        width: 40,
        height: 30,
        ..Default::default()
    };
    let wall = Mesh::from_triangles(
        vec![
            [-9.0, -9.0, 0.0],
            [9.0, -9.0, 0.0],
            [9.0, 9.0, 0.0],
            [-9.0, 9.0, 0.0],
        ],
        &[[0, 1, 2], [0, 2, 3]],
    )
    .unwrap();
    let flat = gbuffer_of(
        &Scene {
            objects: vec![obj(wall, None)],
            ..Default::default()
        },
        &facing,
    );
    for (c, o) in [(&cam, &out), (&facing, &flat)] {
        let r = camera_from_gbuffer(&o.position, &o.depth).unwrap();
        let (a, b) = (c.look_at::<f64>(), r.look_at::<f64>());
        for k in 0..3 {
            assert!(
                (r.eye[k] - c.eye[k]).abs() < 1e-3,
                "{:?} vs {:?}",
                r.eye,
                c.eye
            );
            assert!((a.forward[k] - b.forward[k]).abs() < 1e-5);
            assert!((a.up[k] - b.up[k]).abs() < 1e-5);
        }
        assert!(
            (r.vertical_fov() - c.vertical_fov()).abs() < 1e-5,
            "{} vs {}",
            r.fov_deg,
            c.fov_deg
        );
    }
    let files = cgnodes::node::FileEnv::default();
    let im = |i: &Image| Value::Image(Arc::new(i.clone()));
    let ins = vec![
        ("position", im(&out.position)),
        ("normal", im(&out.normal)),
        ("depth", im(&out.depth)),
    ];
    let mut with_cam = ins.clone();
    with_cam.push(("camera", Value::Camera(Arc::new(cam.clone()))));
    let ao = |ins| match run_node("ssao", ins, &files).unwrap().0["ao"].clone() {
        Value::Image(i) => i,
        _ => panic!(),
    };
    let (a, b) = (ao(ins), ao(with_cam));
    assert!(rmse(&a, &b) < 1e-3, "{}", rmse(&a, &b));
}
