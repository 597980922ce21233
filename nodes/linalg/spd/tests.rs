//! Unit tests of `SpdFactor`.

use super::*;

/// Lower triplets of the 5-point Laplacian (plus a small shift) on the grid points
/// `(i, j)` for which `keep` holds, numbered by `index`.
fn grid_laplacian(
    k: usize,
    keep: impl Fn(usize, usize) -> bool,
    index: impl Fn(usize, usize) -> usize,
) -> Vec<Triplet<usize, usize, f64>> {
    let mut t = Vec::new();
    for i in 0..k {
        for j in 0..k {
            if !keep(i, j) {
                continue;
            }
            t.push(Triplet::new(index(i, j), index(i, j), 4.01));
            for (a, b) in [(i.wrapping_sub(1), j), (i, j.wrapping_sub(1))] {
                if a < k && b < k && keep(a, b) {
                    let (r, c) = (index(i, j), index(a, b));
                    t.push(Triplet::new(r.max(c), r.min(c), -1.0));
                }
            }
        }
    }
    t
}

/// A region of a grid numbered in the whole grid's elimination order fills less than in
/// row-major (banded) order, and `elimination_position` is the inverse permutation.
#[test]
fn elimination_position_orders_a_subgraph_with_little_fill() {
    let k = 40;
    let whole = SpdFactor::new(
        k * k,
        &grid_laplacian(k, |_, _| true, |i, j| i * k + j),
        Par::Seq,
    )
    .unwrap();
    let pos = whole.elimination_position();
    let mut seen = vec![false; k * k];
    for &p in &pos {
        assert!(!seen[p]);
        seen[p] = true;
    }
    // the 20 x 20 block in the middle, numbered by its rank in `pos` or row-major
    let inside = |i: usize, j: usize| (10..30).contains(&i) && (10..30).contains(&j);
    let mut region: Vec<usize> = (0..k * k).filter(|&v| inside(v / k, v % k)).collect();
    let row_major = |i: usize, j: usize| (i - 10) * 20 + (j - 10);
    region.sort_by_key(|&v| pos[v]);
    let mut rank = vec![usize::MAX; k * k];
    for (r, &v) in region.iter().enumerate() {
        rank[v] = r;
    }
    let by_rank = |i: usize, j: usize| rank[i * k + j];
    let fill = |index: &dyn Fn(usize, usize) -> usize| {
        let t = grid_laplacian(k, inside, index);
        let upper: Vec<_> = t
            .iter()
            .map(|e| Triplet::new(e.col, e.row, e.val))
            .collect();
        let a = SparseColMat::<usize, f64>::try_new_from_triplets(400, 400, &upper).unwrap();
        SpdFactor::from_upper_in_order(a, Par::Seq)
            .unwrap()
            .factor_nnz()
    };
    let (ordered, banded) = (fill(&by_rank), fill(&row_major));
    assert!(
        ordered < banded,
        "{ordered} entries in elimination order, {banded} banded"
    );
}

#[test]
fn solves_a_path_laplacian_and_refuses_a_singular_one() {
    let n = 6;
    let mut t = Vec::new();
    for i in 0..n {
        t.push(Triplet::new(i, i, 2.0));
        if i + 1 < n {
            t.push(Triplet::new(i + 1, i, -1.0));
        }
    }
    let f = SpdFactor::new(n, &t, Par::Seq).unwrap();
    // x = i+1 for i < n gives b = 0 except b[n-1] = n+1
    let mut b = faer::Mat::<f64>::zeros(n, 2);
    b[(n - 1, 0)] = (n + 1) as f64;
    b[(n - 1, 1)] = 2.0 * (n + 1) as f64;
    f.solve_in_place(b.as_mut());
    for i in 0..n {
        assert!((b[(i, 0)] - (i + 1) as f64).abs() < 1e-12);
        assert!((b[(i, 1)] - 2.0 * (i + 1) as f64).abs() < 1e-12);
    }
    // pure Neumann: singular
    t[0] = Triplet::new(0, 0, 1.0);
    t[2 * (n - 1)] = Triplet::new(n - 1, n - 1, 1.0);
    assert!(SpdFactor::new(n, &t, Par::Seq).is_err());
    // refactor with doubled values: the solution halves
    t[0] = Triplet::new(0, 0, 2.0);
    t[2 * (n - 1)] = Triplet::new(n - 1, n - 1, 2.0);
    let mut f = SpdFactor::new(n, &t, Par::Seq).unwrap();
    let t2: Vec<_> = t
        .iter()
        .map(|x| Triplet::new(x.row, x.col, 2.0 * x.val))
        .collect();
    f.refactor(&t2, Par::Seq).unwrap();
    let mut b = faer::Mat::<f64>::zeros(n, 1);
    b[(n - 1, 0)] = (n + 1) as f64;
    f.solve_in_place(b.as_mut());
    assert!((b[(0, 0)] - 0.5).abs() < 1e-12);
}

/// The compressed-column copy of a supernodal factor solves like faer's supernodal solve,
/// after the first factorization and after a refactorization (gather path), and a
/// refactorization whose padding is no longer zero rebuilds the pattern.
#[test]
fn column_solves_match_the_supernodal_solve() {
    // 9-point Laplacian of a k x k grid plus a small shift: large enough for supernodes
    let k = 200;
    let id = |i: usize, j: usize| i * k + j;
    let mut t = Vec::new();
    for i in 0..k {
        for j in 0..k {
            t.push(Triplet::new(id(i, j), id(i, j), 6.01));
            if i + 1 < k {
                t.push(Triplet::new(id(i + 1, j), id(i, j), -1.0));
                if j + 1 < k {
                    t.push(Triplet::new(id(i + 1, j + 1), id(i, j), -0.5));
                }
                if j > 0 {
                    t.push(Triplet::new(id(i + 1, j - 1), id(i, j), -0.5));
                }
            }
            if j + 1 < k {
                t.push(Triplet::new(id(i, j + 1), id(i, j), -1.0));
            }
        }
    }
    let n = k * k;
    let b = faer::Mat::<f64>::from_fn(n, 2, |i, c| ((i * 7 + c * 3) % 11) as f64 - 5.0);
    let plain = SpdFactor::new(n, &t, Par::Seq).unwrap();
    let mut fast = SpdFactor::new(n, &t, Par::Seq).unwrap();
    fast.prepare_many_solves();
    assert!(
        fast.columns.is_some(),
        "the grid should factor supernodally"
    );
    let check = |a: &SpdFactor, c: &SpdFactor| {
        let (mut x, mut y) = (b.clone(), b.clone());
        a.solve_in_place(x.as_mut());
        c.solve_in_place(y.as_mut());
        let diff = (&x - &y).norm_max();
        assert!(diff < 1e-12 * x.norm_max(), "difference {diff}");
        assert!(x.norm_max() > 0.1);
    };
    check(&plain, &fast);
    // forward then backward substitution is the whole (permuted) solve
    let (mut x, mut y) = (b.clone(), b.clone());
    plain.solve_in_place(x.as_mut());
    assert!(plain.symbolic.perm().is_some());
    plain.forward_in_place(y.as_mut());
    assert!((&x - &y).norm_max() > 0.1 * x.norm_max());
    plain.backward_in_place(y.as_mut());
    assert!((&x - &y).norm_max() < 1e-12 * x.norm_max());
    // a refactorization with another diagonal shift: values gathered again
    let t2: Vec<_> = t
        .iter()
        .map(|x| {
            Triplet::new(
                x.row,
                x.col,
                if x.row == x.col { x.val + 0.5 } else { x.val },
            )
        })
        .collect();
    let plain2 = SpdFactor::new(n, &t2, Par::Seq).unwrap();
    fast.refactor(&t2, Par::Seq).unwrap();
    check(&plain2, &fast);
    // padding that is no longer zero: rebuilt, still right
    let dropped = fast.dropped.len();
    assert!(dropped > 0, "relaxed supernodes should have zero padding");
    fast.values[fast.dropped[0]] = 1.0;
    fast.update_columns();
    assert_eq!(fast.dropped.len(), dropped - 1);
    fast.refactor(&t2, Par::Seq).unwrap();
    check(&plain2, &fast);
}

/// `solve3` (three interleaved right-hand sides, simplicial factors) agrees with faer's
/// solve, and declines what it does not handle.
#[test]
fn solve3_matches_the_column_solve() {
    let k = 30;
    let f = SpdFactor::new(
        k * k,
        &grid_laplacian(k, |_, _| true, |i, j| i * k + j),
        Par::Seq,
    )
    .unwrap();
    assert!(
        !f.is_supernodal(),
        "a small grid's factor should be simplicial"
    );
    let b = faer::Mat::from_fn(k * k, 3, |i, c| {
        ((i * 7 + c * 13) % 17) as f64 - 8.0 + c as f64 * 0.25
    });
    let mut want = b.clone();
    f.solve_in_place(want.as_mut());
    let mut got = b.clone();
    let mut work = Vec::new();
    assert!(f.solve3(got.as_mut(), &mut work));
    let err = (&got - &want).norm_max() / want.norm_max();
    assert!(err < 1e-13, "relative difference {err:.1e}");
    // a second call reuses the work buffer; two columns are declined
    let mut again = b.clone();
    assert!(f.solve3(again.as_mut(), &mut work));
    assert_eq!(again, got);
    let mut two = b.subcols(0, 2).to_owned();
    assert!(!f.solve3(two.as_mut(), &mut work));
    assert_eq!(two, b.subcols(0, 2).to_owned());
}
