//! ARAP parameterization on real meshes: fold-free mode ends with no flipped triangle on every
//! disk-like mesh in the repository, the energy never increases, and the nodes run in a graph.

use cgnodes::nodes::mesh::obj::load_obj;
use cgnodes::nodes::param::arap::{arap_parameterize, ArapOptions, StopReason};
use cgnodes::nodes::param::tutte::{tutte_parameterize, BoundaryShape, TutteWeights};
use cgnodes::nodes::param::uv_metrics::uv_metrics;
use cgnodes::types::Mesh;
use std::path::Path;
use std::sync::Arc;

fn load(name: &str) -> Arc<Mesh> {
    let p = crate::common::asset(name);
    Arc::new(load_obj(&p, "").unwrap()).triangulated()
}

/// A mesh from the repository, its triangles and the default start (Tutte, mean-value weights,
/// circle, holes filled).
fn with_start(mesh: Arc<Mesh>) -> (Arc<Mesh>, Vec<[u32; 3]>, Vec<[f64; 2]>) {
    let tris = mesh.triangles().unwrap();
    let init =
        tutte_parameterize(&mesh, TutteWeights::MeanValue, BoundaryShape::Circle, true).unwrap();
    (mesh, tris, init)
}

/// Runs fold-free ARAP from the default Tutte start and checks the promises.
fn check_fold_free(name: &str, iterations: usize) -> (f64, f64) {
    let (mesh, tris, init) = with_start(load(name));
    let opts = ArapOptions {
        iterations,
        tolerance: 0.0,
        injective: true,
        ..Default::default()
    };
    let r = arap_parameterize(&mesh.positions, &tris, &init, &opts).unwrap();
    // energy monotone, log complete
    for w in r.log.windows(2) {
        assert!(
            w[1].energy <= w[0].energy,
            "{name}: energy rose {:?} -> {:?}",
            w[0],
            w[1]
        );
        assert!(w[1].step > 0.0);
        assert_eq!(
            w[1].flips, 0,
            "{name}: iteration {} flipped",
            w[1].iteration
        );
    }
    assert!(r.log.len() > 1, "{name}: no iteration accepted");
    assert!(r.energy < r.log[0].energy, "{name}: no progress from Tutte");
    if r.log.len() == iterations + 1 {
        assert_eq!(r.stop_reason, StopReason::Iterations);
    }
    // independent count (uv_metrics, against the majority orientation)
    let m = uv_metrics(&mesh.positions, &tris, &r.uv);
    assert_eq!(m.flipped, 0, "{name}: {} flipped triangles", m.flipped);
    assert_eq!(r.flips, 0);
    (r.log[0].energy, r.energy)
}

#[test]
fn fold_free_on_camelhead() {
    // libigl folds 724 triangles here (bench/peers/arap_libigl.py); a fold-free line search
    // without reweighting stalls at 0.65 of the start's energy
    let (e0, e1) = check_fold_free("assets/meshes/camelhead.obj", 20);
    assert!(e1 < 0.55 * e0, "{e0} -> {e1}");
}

/// The local stiffened re-solve (default) against refactoring the whole Laplacian for every
/// blocked step (`local_rings: 0`), same 30 iterations on camelhead: both fold-free, the local
/// one with far fewer refactorizations and the same energy within 1%.
#[test]
fn local_resolve_replaces_most_refactorizations() {
    let (mesh, tris, init) = with_start(load("assets/meshes/camelhead.obj"));
    let run = |local_rings| {
        let opts = ArapOptions {
            iterations: 30,
            tolerance: 0.0,
            injective: true,
            local_rings,
            ..Default::default()
        };
        let r = arap_parameterize(&mesh.positions, &tris, &init, &opts).unwrap();
        let m = uv_metrics(&mesh.positions, &tris, &r.uv);
        assert_eq!(m.flipped + m.collapsed, 0, "local_rings {local_rings}");
        r
    };
    let (global, local) = (run(0), run(2));
    assert_eq!(global.local_solves, 0);
    assert!(global.refactors > 0 && local.local_solves > 0);
    assert!(
        2 * local.refactors <= global.refactors,
        "refactorizations: local {} global {}",
        local.refactors,
        global.refactors
    );
    assert!(
        local.energy <= 1.01 * global.energy,
        "energy: local {} global {}",
        local.energy,
        global.energy
    );
}

#[test]
fn fold_free_on_camel_b() {
    check_fold_free("assets/meshes/camel_b.obj", 30);
}

#[test]
fn fold_free_on_nefertiti_front() {
    check_fold_free("assets/meshes/nefertiti_front.obj", 8);
}

#[test]
fn fold_free_on_beetle_with_holes() {
    // 11 boundary loops: Tutte fills the holes for the start, ARAP keeps them free
    check_fold_free("assets/meshes/beetle_11holes.obj", 20);
}

#[test]
fn plain_mode_energy_is_monotone_too() {
    let (mesh, tris, init) = with_start(load("assets/meshes/camel_b.obj"));
    let opts = ArapOptions {
        iterations: 40,
        tolerance: 0.0,
        injective: false,
        ..Default::default()
    };
    let r = arap_parameterize(&mesh.positions, &tris, &init, &opts).unwrap();
    for w in r.log.windows(2) {
        assert!(w[1].energy <= w[0].energy, "{:?} -> {:?}", w[0], w[1]);
    }
    // Both energies are Liu et al.'s `Σ A ((σ1-1)² + (σ2-1)²) / Σ A`; they differ only because
    // uv_metrics first scales the UVs by `uv_scale` (total UV area = total 3-D area). Computed
    // here from the Jacobians at scale 1 and at `uv_scale`, each must match to rounding.
    let m = uv_metrics(&mesh.positions, &tris, &r.uv);
    assert!(
        (m.uv_scale - 1.0).abs() < 0.1,
        "ARAP keeps the size: {}",
        m.uv_scale
    );
    assert_eq!(m.degenerate, 0);
    let own = arap_energy_at_scale(&mesh.positions, &tris, &r.uv, 1.0);
    assert!(
        (own - r.energy).abs() <= 1e-9 * r.energy,
        "ARAP energy {} vs direct {own}",
        r.energy
    );
    let scaled = arap_energy_at_scale(&mesh.positions, &tris, &r.uv, m.uv_scale);
    assert!(
        (scaled - m.arap_energy).abs() <= 1e-9 * m.arap_energy,
        "uv_metrics {} vs direct {scaled} at scale {}",
        m.arap_energy,
        m.uv_scale
    );
    // The rescaling matters here: the two energies are not the same number.
    assert!((m.arap_energy - r.energy).abs() > 1e-6 * r.energy);
}

/// Liu et al. 2008's ARAP energy (eq. 3 in the singular-value form) of the UVs scaled by `s`:
/// `Σ A ((s σ1 - 1)² + (s σ2 - 1)²) / Σ A` over the 3-D triangle areas `A`, with `σ1 >= |σ2|`
/// the signed singular values of each triangle's Jacobian (`σ2 < 0` when it is flipped).
fn arap_energy_at_scale(p: &[[f64; 3]], tris: &[[u32; 3]], uv: &[[f64; 2]], s: f64) -> f64 {
    use cgnodes::nodes::param::uv_metrics::{signed_singular_values_2x2, triangle_jacobian};
    let (mut e, mut area) = (0.0, 0.0);
    for t in tris {
        let (j, a) = triangle_jacobian(t.map(|v| p[v as usize]), t.map(|v| uv[v as usize]))
            .expect("no degenerate triangle");
        let (s1, s2) = signed_singular_values_2x2(j[0], j[1], j[2], j[3]);
        e += a * ((s * s1 - 1.0).powi(2) + (s * s2 - 1.0).powi(2));
        area += a;
    }
    e / area
}

#[test]
fn fold_free_on_every_course_disk_mesh() {
    use cgnodes::nodes::mesh::mesh_load::{load_mesh, LoadOptions};
    // every disk-like course mesh (Beetle_ABF has 11 holes, filled for the Tutte start)
    for name in [
        "Beetle_ABF",
        "Cow_dABF",
        "Isis_dABF",
        "Gargoyle_ABF",
        "NefertitiFace",
        "BunnyHead",
        "CatHead",
        "David328",
        "grid10x10",
    ] {
        let p = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("assets/course/{name}.usda"));
        let opts = LoadOptions {
            prim: String::new(),
            group: String::new(),
            apply_transform: true,
        };
        let (mesh, tris, init) = with_start(Arc::new(load_mesh(&p, &opts).unwrap()).triangulated());
        let arap = ArapOptions {
            iterations: 15,
            ..Default::default()
        };
        let r = arap_parameterize(&mesh.positions, &tris, &init, &arap).unwrap();
        let m = uv_metrics(&mesh.positions, &tris, &r.uv);
        assert_eq!((m.flipped, m.collapsed, r.flips), (0, 0, 0), "{name}");
        assert!(r.energy < r.log[0].energy, "{name}");
        for w in r.log.windows(2) {
            assert!(w[1].energy <= w[0].energy, "{name}");
        }
    }
}

#[test]
fn fold_free_long_run_keeps_area_floor_and_is_deterministic() {
    // With tolerance 0 and many iterations, a blocked triangle used to be allowed to halve its
    // area every iteration (collapse), and parallel sums in scheduling order made the run
    // differ between calls. Now each triangle keeps its UV area above
    // min(1e-6 · its 3-D area · start ratio, half its start area), and sums are ordered.
    use cgnodes::nodes::param::arap::frames::TriangleFrames;
    let (mesh, tris, init) = with_start(load("assets/meshes/camel_b.obj"));
    let opts = ArapOptions {
        iterations: 150,
        tolerance: 0.0,
        injective: true,
        ..Default::default()
    };
    let a = arap_parameterize(&mesh.positions, &tris, &init, &opts).unwrap();
    let b = arap_parameterize(&mesh.positions, &tris, &init, &opts).unwrap();
    assert_eq!(a.log.len(), b.log.len(), "stopping iteration differs");
    for (x, y) in a.log.iter().zip(&b.log) {
        assert_eq!(
            (x.energy.to_bits(), x.step.to_bits(), x.refactors),
            (y.energy.to_bits(), y.step.to_bits(), y.refactors),
            "iteration {}",
            x.iteration
        );
    }
    assert_eq!(a.uv, b.uv);
    assert!(
        a.refactors + a.local_solves > 0,
        "camel_b blocks: the fold-free mode must stiffen (locally or by refactoring)"
    );
    let f = TriangleFrames::new(&mesh.positions, &tris).unwrap();
    let orient = if (0..f.len()).map(|t| f.signed_area2(t, &init)).sum::<f64>() > 0.0 {
        1.0
    } else {
        -1.0
    };
    let a0: Vec<f64> = (0..f.len())
        .map(|t| orient * f.signed_area2(t, &init))
        .collect();
    let ratio0 = a0.iter().sum::<f64>() / (2.0 * f.total_area);
    for (t, &start) in a0.iter().enumerate() {
        let floor = (1e-6 * 2.0 * f.area[t] * ratio0).min(0.5 * start);
        let now = orient * f.signed_area2(t, &a.uv);
        // The step to the floor is the root of a quadratic in the step length, solved in
        // floating point where the floor is ~1e-10 against UVs of size ~1: allow 0.1 %.
        assert!(
            now >= floor * (1.0 - 1e-3),
            "triangle {t}: twice the area {now:e} below its floor {floor:e}"
        );
    }
    let m = uv_metrics(&mesh.positions, &tris, &a.uv);
    assert_eq!((m.flipped, m.collapsed, a.flips), (0, 0, 0));
}

#[test]
fn fold_free_runs_are_bit_identical_on_a_many_chunk_mesh() {
    // 44k triangles: 22 chunks of 2048, so an unordered parallel sum could differ between
    // runs; the ordered sums make the logs bit-identical
    let (mesh, tris, init) = with_start(load("assets/meshes/nefertiti_front.obj"));
    let opts = ArapOptions {
        iterations: 12,
        tolerance: 0.0,
        ..Default::default()
    };
    let runs: Vec<Vec<(u64, u64)>> = (0..3)
        .map(|_| {
            let r = arap_parameterize(&mesh.positions, &tris, &init, &opts).unwrap();
            r.log
                .iter()
                .map(|x| (x.energy.to_bits(), x.step.to_bits()))
                .collect()
        })
        .collect();
    assert_eq!(runs[0].len(), 13);
    assert_eq!(runs[0], runs[1]);
    assert_eq!(runs[0], runs[2]);
}

/// `init_uv` (a UV list, one per vertex, as a Framework3D Float2Buffer) starts ARAP exactly
/// where an `init` mesh carrying the same UVs does; both at once, or a wrong length, is an
/// error naming `init_uv`.
#[test]
fn init_uv_list_starts_like_an_init_mesh() {
    use cgnodes::node::FileEnv;
    use cgnodes::types::{Attribute, Domain, Value};
    let mut m =
        cgnodes::nodes::mesh::mesh_grid::grid_mesh(4, 4, [2.0, 2.0], "xy", [0.0; 3], true).unwrap();
    for p in &mut m.positions {
        p[2] = 0.3 * (p[0] * p[1]).sin(); // not flat: the start matters
    }
    let mesh = Arc::new(m);
    let uv = tutte_parameterize(&mesh, TutteWeights::Uniform, BoundaryShape::Square, true).unwrap();
    let mut init = (*mesh).clone();
    init.uvs = Some(Attribute {
        domain: Domain::Vertex,
        values: uv.clone(),
    });
    let list =
        |uv: &[[f64; 2]]| Value::List(Arc::new(uv.iter().map(|&x| Value::from(x)).collect()));
    let run = |ins: Vec<(&str, Value)>| {
        let mut all = vec![
            ("mesh", Value::from(mesh.clone())),
            ("iterations", Value::from(3i64)),
        ];
        all.extend(ins);
        crate::common::run_node("arap", all, &FileEnv::default())
    };
    let flat = |o: &crate::common::NodeOutputs| match &o.0["flat"] {
        Value::Mesh(m) => m.positions.clone(),
        _ => panic!("no flat output"),
    };
    let a = run(vec![("init", Value::from(init.clone()))]).unwrap();
    let b = run(vec![("init_uv", list(&uv))]).unwrap();
    assert_eq!(flat(&a), flat(&b));
    assert!(b.1.iter().any(|l| l.contains("init_uv")), "{:?}", b.1);
    let e = run(vec![("init", Value::from(init)), ("init_uv", list(&uv))]).unwrap_err();
    assert!(e.contains("init_uv"), "{e}");
    let e = run(vec![("init_uv", list(&uv[1..]))]).unwrap_err();
    assert!(
        e.contains("init_uv") && e.contains("24 UVs for 25 vertices"),
        "{e}"
    );
}
