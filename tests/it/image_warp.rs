//! `image_warp`: the issue's acceptance tests (identity, interpolation, affine and rigid
//! reproduction, every bad input with its socket) on the course's test image.

use crate::common::{asset, run_graph};
use cgnodes::node::Choice;
use cgnodes::nodes::builtin_registry;
use cgnodes::nodes::image::image_load::{decode_image, ColorSpace};
use cgnodes::nodes::image::warp::{
    fit, residual, warp_image, Fill, Kernel, Mapping, Method, WarpParams,
};
use cgnodes::types::Image;

fn test_image() -> Image {
    let bytes = std::fs::read(asset("assets/images/test.png")).unwrap();
    decode_image(&bytes, ColorSpace::Srgb).unwrap()
}

/// Deterministic pseudo-random numbers in [0, 1) (a 64-bit LCG), so the tests need no crate.
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    fn points(&mut self, n: usize, size: f64) -> Vec<[f64; 2]> {
        (0..n)
            .map(|_| [self.next() * size, self.next() * size])
            .collect()
    }
}

/// Every method, and for RBF every kernel with the automatic and a fixed radius.
fn all_params() -> Vec<WarpParams> {
    let mut v = Vec::new();
    for (_, method) in Method::CHOICES {
        if *method == Method::Rbf {
            for (_, kernel) in Kernel::CHOICES {
                for radius in [0.0, 40.0] {
                    v.push(WarpParams {
                        method: *method,
                        kernel: *kernel,
                        radius,
                        ..Default::default()
                    });
                }
            }
        } else {
            for (mu, alpha) in [(2.0, 1.0), (3.0, 0.5)] {
                v.push(WarpParams {
                    method: *method,
                    mu,
                    alpha,
                    ..Default::default()
                });
            }
        }
    }
    v
}

#[test]
fn identity_control_points_give_the_input_back_exactly() {
    let img = test_image();
    let p = Lcg(7).points(6, 256.0);
    for params in all_params() {
        for grid in [0, 8] {
            let r = warp_image(&img, &p, &p, &params, Mapping::Inverse, Fill::None, grid).unwrap();
            assert!(r.image == img, "{params:?} grid {grid}");
            assert_eq!(r.outside, 0);
            // Forward mapping moves every centre onto itself: no hole either.
            let r = warp_image(&img, &p, &p, &params, Mapping::Forward, Fill::None, grid).unwrap();
            assert!(
                r.image == img && r.hole_count == 0,
                "{params:?} grid {grid}"
            );
        }
    }
}

#[test]
fn every_method_interpolates_its_control_points() {
    let mut rng = Lcg(11);
    for params in all_params() {
        for _ in 0..3 {
            let p = rng.points(8, 256.0);
            let q: Vec<[f64; 2]> = p
                .iter()
                .map(|x| {
                    [
                        x[0] + 30.0 * (rng.next() - 0.5),
                        x[1] + 30.0 * (rng.next() - 0.5),
                    ]
                })
                .collect();
            let f = fit(&params, &p, &q).unwrap();
            let res = residual(f.as_ref(), &p, &q);
            assert!(res < 1e-6, "{params:?}: residual {res}");
            // The image warp reports the residual of the map it fitted.
            let r = warp_image(
                &test_image(),
                &p,
                &q,
                &params,
                Mapping::Forward,
                Fill::None,
                0,
            )
            .unwrap();
            assert!(r.residual < 1e-6);
        }
    }
}

#[test]
fn affine_control_sets_are_reproduced_by_rbf_and_mls_affine() {
    let mut rng = Lcg(3);
    let (a, b) = ([[1.2, -0.3], [0.25, 0.85]], [14.0, -9.0]);
    let affine = |x: &[f64; 2]| {
        [
            a[0][0] * x[0] + a[0][1] * x[1] + b[0],
            a[1][0] * x[0] + a[1][1] * x[1] + b[1],
        ]
    };
    let p = rng.points(10, 256.0);
    let q: Vec<[f64; 2]> = p.iter().map(affine).collect();
    let mut params: Vec<WarpParams> = all_params()
        .into_iter()
        .filter(|w| w.method == Method::Rbf)
        .collect();
    params.push(WarpParams {
        method: Method::MlsAffine,
        ..Default::default()
    });
    for w in params {
        let f = fit(&w, &p, &q).unwrap();
        for x in rng.points(50, 300.0) {
            let (y, e) = (f.eval(x), affine(&x));
            assert!(
                (y[0] - e[0]).abs() < 1e-9 && (y[1] - e[1]).abs() < 1e-9,
                "{w:?} at {x:?}: {y:?} against {e:?}"
            );
        }
    }
}

#[test]
fn mls_rigid_maps_a_rotated_set_by_the_same_rotation() {
    let mut rng = Lcg(5);
    let (c, s) = (0.7f64.cos(), 0.7f64.sin());
    let rot = |x: &[f64; 2]| [c * x[0] - s * x[1] + 40.0, s * x[0] + c * x[1] - 25.0];
    let p = rng.points(7, 256.0);
    let q: Vec<[f64; 2]> = p.iter().map(rot).collect();
    for method in [Method::MlsRigid, Method::MlsSimilarity] {
        let w = WarpParams {
            method,
            ..Default::default()
        };
        let f = fit(&w, &p, &q).unwrap();
        for x in rng.points(50, 256.0) {
            let (y, e) = (f.eval(x), rot(&x));
            assert!((y[0] - e[0]).abs() < 1e-9 && (y[1] - e[1]).abs() < 1e-9);
        }
    }
}

/// Runs an `image_warp` graph on the test image with `params` (JSON members) and returns the
/// run's error messages.
fn warp_errors(params: &str, files: &[(&str, &str)]) -> Vec<String> {
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(asset("assets/images/test.png"), dir.path().join("test.png")).unwrap();
    for (name, text) in files {
        std::fs::write(dir.path().join(name), text).unwrap();
    }
    let out = dir.path().join("out");
    let graph = format!(
        r#"{{"format": "cgnodes-graph", "version": 1, "nodes": {{
            "load": {{"type": "image_load", "params": {{"path": "test.png"}}}},
            "warp": {{"type": "image_warp", "params": {{{params}}}, "inputs": {{"image": "load.image"}}}},
            "save": {{"type": "image_save", "params": {{"path": "w.png"}}, "inputs": {{"image": "warp.image"}}}}
        }}}}"#
    );
    let reports = run_graph(&graph, &builtin_registry(), dir.path(), &out, 1, 0..=0);
    reports[0].errors()
}

/// Graph parameters, extra files, the socket the error names and words in its message.
type Case<'a> = (&'a str, &'a [(&'a str, &'a str)], &'a str, &'a str);

#[test]
fn a_good_graph_runs_and_bad_inputs_name_their_socket() {
    let ok = r#""source_points": [[50, 50], [200, 60], [120, 200]],
                "target_points": [[60, 40], [190, 70], [120, 180]], "method": "mls_rigid""#;
    assert!(
        warp_errors(ok, &[]).is_empty(),
        "{:?}",
        warp_errors(ok, &[])
    );
    let file = "sx,sy,tx,ty\n50,50,60,40\n200,60,190,70\n120,200,120,180\n";
    let ok =
        r#""points_file": "pts.csv", "method": "rbf", "mapping": "forward", "fill": "push_pull""#;
    assert!(warp_errors(ok, &[("pts.csv", file)]).is_empty());
    let cases: [Case; 7] = [
        (
            r#""source_points": [[1, 2], [3, 4]], "target_points": [[1, 2]]"#,
            &[],
            "target_points",
            "counts must be equal",
        ),
        (
            r#""source_points": [[1, 2], [3, 4]], "target_points": [[1, 2], [3, 4]], "method": "rbf""#,
            &[],
            "source_points",
            "needs at least 3",
        ),
        (
            r#""source_points": [[1, 2], [3, 4]], "target_points": [[1, 2], [3, 4]], "method": "mls_affine", "mapping": "forward""#,
            &[],
            "source_points",
            "needs at least 3",
        ),
        (
            r#""source_points": [[1, 2], [30, 4], [5, 60]], "target_points": [[1, 2], [1, 2], [5, 60]], "method": "rbf""#,
            &[],
            "target_points",
            "coincide",
        ),
        (
            r#""source_points": [[1, 2], [1, 2], [5, 60]], "target_points": [[1, 2], [30, 4], [5, 60]], "method": "rbf", "mapping": "forward""#,
            &[],
            "source_points",
            "coincide",
        ),
        (
            r#""points_file": "nan.csv""#,
            &[("nan.csv", "sx,sy,tx,ty\n1,2,3,4\nNaN,2,3,4\n")],
            "points_file",
            "NaN",
        ),
        (r#""source_points": [[1, 2]]"#, &[], "target_points", "not"),
    ];
    for (params, files, socket, words) in cases {
        let errs = warp_errors(params, files);
        assert!(!errs.is_empty(), "{params}: no error");
        assert!(
            errs[0].contains(&format!("socket '{socket}'")) && errs[0].contains(words),
            "{params}: {}",
            errs[0]
        );
    }
}

#[test]
fn nan_and_collinear_points_are_refused_by_the_algorithm() {
    let img = Image::new(8, 8, [1.0; 4]);
    let p = [[1.0, 1.0], [5.0, 2.0], [f64::NAN, 6.0]];
    let q = [[1.0, 1.0], [5.0, 2.0], [3.0, 6.0]];
    let w = WarpParams::default();
    let e = warp_image(&img, &p, &q, &w, Mapping::Forward, Fill::None, 0).unwrap_err();
    assert!(e.to_string().contains("NaN"));
    let line = [[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]];
    let rbf = WarpParams {
        method: Method::Rbf,
        ..Default::default()
    };
    let e = warp_image(&img, &line, &q, &rbf, Mapping::Forward, Fill::None, 0).unwrap_err();
    assert!(e.to_string().contains("one line"));
}
