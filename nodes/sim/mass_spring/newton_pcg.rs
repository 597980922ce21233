//! The Newton system of `implicit.rs`, `H dx = -grad g`, solved matrix-free by preconditioned
//! conjugate gradients (faer's `conjugate_gradient`; Hestenes & Stiefel 1952), as Baraff &
//! Witkin 1998 (§5) solve their cloth systems.
//!
//! `H = M/h^2 + sum_s K_s (+ the penalty's k_p n n^T)` is never assembled: each Newton step
//! stores one PSD 3x3 block per spring (`spring_hessian_psd`, the per-spring projection that
//! keeps `H` positive definite without any refactorization) and `H p` is gathered per vertex,
//! `(H p)_v = (m_v/h^2 + C_v) p_v + sum_{s = (v, u)} K_s (p_v - p_u)`. The preconditioner is
//! block Jacobi: the inverse of each vertex's 3x3 diagonal block of `H`.
//!
//! Vectors have three entries per vertex, fixed vertices included: their entries are zero in
//! the right-hand side, the preconditioner and the operator's output, so every Krylov vector
//! stays in the free subspace and CG solves the reduced system `S^T H S` of the direct path.
//!
//! The solve is inexact on purpose (an inexact Newton method, Dembo, Eisenstat & Steihaug
//! 1982): CG stops when `|H dx + grad| <= cg_tol |grad|`. Any CG iterate from a zero start is
//! a descent direction for SPD `H`, so the line search keeps working; near the minimizer the
//! step error is `cg_tol` times a step already below the Newton tolerance.

use super::springs::{spring_hessian_psd, sub, Model, Sphere};
use cgnodes_linalg as linalg;
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::matrix_free::conjugate_gradient::{
    conjugate_gradient, conjugate_gradient_scratch, CgParams,
};
use faer::matrix_free::{InitialGuessStatus, LinOp, Precond};
use faer::{Mat, MatMut, MatRef, Par};
use rayon::prelude::*;

/// A symmetric 3x3 block stored as `(xx, xy, xz, yy, yz, zz)`.
type Sym3 = [f64; 6];

/// Vertices per rayon task in the per-vertex loops (below this the loops run serially).
const PAR_MIN_VERTICES: usize = 4096;
/// Springs per rayon task when the spring blocks are evaluated.
const PAR_MIN_SPRINGS: usize = 8192;

/// The per-spring Hessian blocks of one Newton step and the workspace of its CG solves.
pub struct HessianPcg {
    /// Springs around each vertex in compressed rows: start of each vertex's list.
    start: Vec<usize>,
    /// Other end and spring index of each incident spring.
    adj: Vec<(u32, u32)>,
    free: Vec<bool>,
    /// Each spring's PSD Hessian block at the current iterate.
    blocks: Vec<Sym3>,
    /// Each vertex's diagonal block without its springs: `m/h^2 I` plus the penalty's block.
    diag: Vec<Sym3>,
    /// Inverse of each free vertex's full diagonal block (zero for fixed vertices).
    inv: Vec<Sym3>,
    /// The first Newton direction of the previous step, the first CG's initial guess.
    warm: Option<Mat<f64>>,
    mem: Option<MemBuffer>,
    /// The per-axis Laplacian preconditioner (`AxisLaplacians`), when used.
    axes: Option<AxisLaplacians>,
    /// Which preconditioner CG uses.
    pub preconditioner: Preconditioner,
}

/// The preconditioner of the Newton systems' CG.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Preconditioner {
    /// `BlockJacobi` until one of its CG solves takes more than `STIFF_CG_ITERS` iterations
    /// (stiff springs for their mass), then `AxisLaplacians` for the rest of the simulation.
    #[default]
    Auto,
    /// The inverse of each vertex's 3x3 diagonal block: cheap per iteration (a tenth of a
    /// millisecond at 128x128), but its CG iterations grow with stiffness per mass.
    BlockJacobi,
    /// Sparse Cholesky factors of the three per-axis Laplacians of the Hessian
    /// (`AxisLaplacians`), reused across Newton iterations and steps while they pay: CG
    /// iterations that do not grow with stiffness, at a few milliseconds per iteration.
    AxisLaplacians,
}

/// `Preconditioner::Auto` leaves block Jacobi after a CG solve longer than this.
pub const STIFF_CG_ITERS: usize = 100;

/// Why a CG solve of a Newton system failed (the caller falls back to the sparse Cholesky).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum PcgError {
    /// faer's conjugate gradient stopped without converging (its error, as `Debug`).
    #[error("conjugate gradient: {0}")]
    Cg(String),
    /// An axis-Laplacian preconditioner factor failed (`SpdFactor`'s reason).
    #[error("{0}")]
    Preconditioner(String),
}

/// What a CG solve did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CgOutcome {
    /// CG iterations.
    pub iterations: usize,
    /// Final `|H dx - rhs| / |rhs|`.
    pub rel_residual: f64,
}

impl HessianPcg {
    /// The vertex-to-spring adjacency of `m`; the blocks are filled by `assemble`.
    pub fn new(m: &Model) -> HessianPcg {
        let n = m.num_vertices();
        let mut start = vec![0usize; n + 1];
        for e in &m.springs.ends {
            start[e[0] as usize + 1] += 1;
            start[e[1] as usize + 1] += 1;
        }
        for i in 0..n {
            start[i + 1] += start[i];
        }
        let mut fill = start.clone();
        let mut adj = vec![(0u32, 0u32); start[n]];
        for (s, e) in m.springs.ends.iter().enumerate() {
            for (v, u) in [(e[0], e[1]), (e[1], e[0])] {
                adj[fill[v as usize]] = (u, s as u32);
                fill[v as usize] += 1;
            }
        }
        HessianPcg {
            start,
            adj,
            free: m.fixed.iter().map(|f| !f).collect(),
            blocks: vec![[0.0; 6]; m.springs.len()],
            diag: vec![[0.0; 6]; n],
            inv: vec![[0.0; 6]; n],
            warm: None,
            mem: None,
            axes: None,
            preconditioner: Preconditioner::default(),
        }
    }

    /// Evaluates the Hessian of `g` at `x` (`ih2 = 1/h^2`): the spring blocks, the diagonal
    /// blocks and their inverses (the preconditioner).
    pub fn assemble(&mut self, m: &Model, x: &[[f64; 3]], ih2: f64, sp: Option<&Sphere>) {
        let springs = &m.springs;
        self.blocks
            .par_iter_mut()
            .with_min_len(PAR_MIN_SPRINGS)
            .enumerate()
            .for_each(|(s, b)| {
                let [i, j] = springs.ends[s];
                let k = spring_hessian_psd(
                    sub(x[j as usize], x[i as usize]),
                    springs.rest[s],
                    springs.k[s],
                );
                *b = [k[0][0], k[0][1], k[0][2], k[1][1], k[1][2], k[2][2]];
            });
        let (blocks, start, adj, free) = (&self.blocks, &self.start, &self.adj, &self.free);
        let contact = sp.map(|s| (s.center, s.contact_radius(), s.k));
        self.diag
            .par_iter_mut()
            .zip(self.inv.par_iter_mut())
            .with_min_len(PAR_MIN_VERTICES)
            .enumerate()
            .for_each(|(v, (d, inv))| {
                if !free[v] {
                    (*d, *inv) = ([0.0; 6], [0.0; 6]);
                    return;
                }
                let mv = m.mass[v] * ih2;
                let mut own = [mv, 0.0, 0.0, mv, 0.0, mv];
                if let Some((c, r, kp)) = contact {
                    // Gauss-Newton (PSD) part of the penalty Hessian: k_p n n^T.
                    let dd = sub(x[v], c);
                    let l = super::springs::norm(dd);
                    if l < r && l > 0.0 {
                        let nn = [dd[0] / l, dd[1] / l, dd[2] / l];
                        let outer = [
                            nn[0] * nn[0],
                            nn[0] * nn[1],
                            nn[0] * nn[2],
                            nn[1] * nn[1],
                            nn[1] * nn[2],
                            nn[2] * nn[2],
                        ];
                        for (o, e) in own.iter_mut().zip(outer) {
                            *o += kp * e;
                        }
                    }
                }
                let mut full = own;
                for &(_, s) in &adj[start[v]..start[v + 1]] {
                    for (f, b) in full.iter_mut().zip(&blocks[s as usize]) {
                        *f += b;
                    }
                }
                *d = own;
                *inv = sym3_inverse(&full);
            });
    }

    /// Solves `H dx = rhs` (three entries per vertex, zero at fixed vertices) to
    /// `|H dx - rhs| <= rel_tol |rhs|`, from the previous step's first direction when
    /// `first` (the first Newton iteration of a step) and from zero otherwise. `Err` when CG
    /// does not converge within `max_iters` or finds `H` not positive definite (the caller
    /// then falls back to the sparse Cholesky).
    pub fn solve(
        &mut self,
        rhs: MatRef<'_, f64>,
        mut dx: MatMut<'_, f64>,
        first: bool,
        rel_tol: f64,
        max_iters: usize,
    ) -> Result<CgOutcome, PcgError> {
        match (&self.warm, first) {
            (Some(w), true) if w.nrows() == dx.nrows() => dx.copy_from(w.as_ref()),
            _ => dx.fill(0.0),
        }
        let op = Operator {
            start: &self.start,
            adj: &self.adj,
            blocks: &self.blocks,
            diag: &self.diag,
            free: &self.free,
        };
        let par = Par::Seq;
        let params = CgParams {
            // faer 0.24 leaves the residual unset for `Zero`; the guess is filled above
            initial_guess: InitialGuessStatus::MaybeNonZero,
            abs_tolerance: 0.0,
            rel_tolerance: rel_tol,
            max_iters,
            ..Default::default()
        };
        let pre = match self.preconditioner {
            Preconditioner::AxisLaplacians => {
                let axes = self
                    .axes
                    .get_or_insert_with(|| AxisLaplacians::new(&self.start, &self.adj, &self.free));
                axes.update(&self.start, &self.adj, &self.blocks, &self.diag)?;
                Pre::Axes(axes)
            }
            Preconditioner::BlockJacobi | Preconditioner::Auto => Pre::Jacobi(&self.inv),
        };
        let mem = self
            .mem
            .get_or_insert_with(|| MemBuffer::new(conjugate_gradient_scratch(&pre, &op, 1, par)));
        let info = conjugate_gradient(
            dx.as_mut(),
            &pre,
            &op,
            rhs,
            params,
            |_| {},
            par,
            MemStack::new(mem),
        )
        .map_err(|e| PcgError::Cg(format!("{e:?}")))?;
        match (self.preconditioner, self.axes.as_mut()) {
            (Preconditioner::AxisLaplacians, Some(axes)) => axes.record(info.iter_count),
            (Preconditioner::Auto, _) if info.iter_count > STIFF_CG_ITERS => {
                self.preconditioner = Preconditioner::AxisLaplacians;
            }
            _ => {}
        }
        if first {
            match &mut self.warm {
                Some(w) if w.nrows() == dx.nrows() => w.copy_from(dx.as_ref()),
                w => *w = Some(dx.to_owned()),
            }
        }
        Ok(CgOutcome {
            iterations: info.iter_count,
            rel_residual: info.rel_residual,
        })
    }

    /// `out = H p` (three entries per vertex), for tests and diagnostics.
    pub fn apply(&self, p: &[f64], out: &mut [f64]) {
        Operator {
            start: &self.start,
            adj: &self.adj,
            blocks: &self.blocks,
            diag: &self.diag,
            free: &self.free,
        }
        .gather(p, out);
    }
}

/// `H` as a faer linear operator over the current blocks.
struct Operator<'a> {
    start: &'a [usize],
    adj: &'a [(u32, u32)],
    blocks: &'a [Sym3],
    diag: &'a [Sym3],
    free: &'a [bool],
}

impl Operator<'_> {
    fn gather(&self, p: &[f64], out: &mut [f64]) {
        let at = |u: usize| [p[3 * u], p[3 * u + 1], p[3 * u + 2]];
        out.par_chunks_mut(3)
            .with_min_len(PAR_MIN_VERTICES)
            .enumerate()
            .for_each(|(v, o)| {
                if !self.free[v] {
                    o.fill(0.0);
                    return;
                }
                let pv = at(v);
                let mut acc = sym3_mul(&self.diag[v], pv);
                for &(u, s) in &self.adj[self.start[v]..self.start[v + 1]] {
                    let u = u as usize;
                    let d = if self.free[u] { sub(pv, at(u)) } else { pv };
                    let k = sym3_mul(&self.blocks[s as usize], d);
                    acc = [acc[0] + k[0], acc[1] + k[1], acc[2] + k[2]];
                }
                o.copy_from_slice(&acc);
            });
    }
}

/// Applies `f(rhs column, out column)` to each column, through contiguous slices when the
/// columns are contiguous (faer's CG passes such columns) and through copies otherwise.
fn per_column(mut out: MatMut<'_, f64>, rhs: MatRef<'_, f64>, f: impl Fn(&[f64], &mut [f64])) {
    for j in 0..rhs.ncols() {
        let src = rhs.col(j);
        if let (Some(s), Some(d)) = (
            src.try_as_col_major(),
            out.as_mut().col_mut(j).try_as_col_major_mut(),
        ) {
            f(s.as_slice(), d.as_slice_mut());
            continue;
        }
        let s: Vec<f64> = (0..src.nrows()).map(|i| src[i]).collect();
        let mut d = vec![0.0; s.len()];
        f(&s, &mut d);
        for (i, v) in d.into_iter().enumerate() {
            out[(i, j)] = v;
        }
    }
}

impl std::fmt::Debug for Operator<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "mass-spring Hessian ({} vertices)", self.free.len())
    }
}

impl LinOp<f64> for Operator<'_> {
    fn apply_scratch(&self, _rhs_ncols: usize, _par: Par) -> StackReq {
        StackReq::EMPTY
    }
    fn nrows(&self) -> usize {
        3 * self.free.len()
    }
    fn ncols(&self) -> usize {
        3 * self.free.len()
    }
    fn apply(&self, out: MatMut<'_, f64>, rhs: MatRef<'_, f64>, _par: Par, _: &mut MemStack) {
        per_column(out, rhs, |p, o| self.gather(p, o));
    }
    fn conj_apply(&self, out: MatMut<'_, f64>, rhs: MatRef<'_, f64>, par: Par, s: &mut MemStack) {
        self.apply(out, rhs, par, s);
    }
}

/// The preconditioner a CG solve applies.
enum Pre<'a> {
    /// Block Jacobi: each free vertex's inverted 3x3 diagonal block (zero for fixed ones).
    Jacobi(&'a [Sym3]),
    /// The per-axis Laplacians.
    Axes(&'a AxisLaplacians),
}

impl std::fmt::Debug for Pre<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Pre::Jacobi(inv) => write!(f, "block Jacobi ({} vertices)", inv.len()),
            Pre::Axes(a) => write!(f, "per-axis Laplacians ({} vertices)", a.row.len()),
        }
    }
}

impl LinOp<f64> for Pre<'_> {
    fn apply_scratch(&self, _rhs_ncols: usize, _par: Par) -> StackReq {
        StackReq::EMPTY
    }
    fn nrows(&self) -> usize {
        3 * match self {
            Pre::Jacobi(inv) => inv.len(),
            Pre::Axes(a) => a.row.len(),
        }
    }
    fn ncols(&self) -> usize {
        self.nrows()
    }
    fn apply(&self, out: MatMut<'_, f64>, rhs: MatRef<'_, f64>, _par: Par, _: &mut MemStack) {
        per_column(out, rhs, |p, o| match self {
            Pre::Jacobi(inv) => {
                for (v, ov) in o.chunks_mut(3).enumerate() {
                    ov.copy_from_slice(&sym3_mul(&inv[v], [p[3 * v], p[3 * v + 1], p[3 * v + 2]]));
                }
            }
            Pre::Axes(a) => a.solve(p, o),
        });
    }
    fn conj_apply(&self, out: MatMut<'_, f64>, rhs: MatRef<'_, f64>, par: Par, s: &mut MemStack) {
        self.apply(out, rhs, par, s);
    }
}

impl Precond<f64> for Pre<'_> {}

/// Separate displacement components (Axelsson & Gustafsson's block-diagonal preconditioner
/// for elasticity; Axelsson 1999, "Stabilization of algebraic multilevel iteration methods"):
/// for each axis `a`, the scalar matrix `P_a = M/h^2 + sum_s w_s^a (e_u - e_v)(e_u - e_v)^T`
/// with `w_s^a` the `aa` entry of spring `s`'s PSD block, a weighted graph Laplacian over the
/// free vertices plus the mass. It keeps what block Jacobi loses on stiff cloth: the
/// coupling of a vertex to its neighbours, so the CG iterations no longer grow with the
/// stiffness per mass; it drops only the coupling between axes.
///
/// The three factors share one pattern (symbolic analysis once) and are refactored only when
/// they stop paying: when a CG needs more than twice the iterations of the first CG after the
/// last refactorization (and more than `REFACTOR_MIN_ITERS`).
pub struct AxisLaplacians {
    /// Row of each free vertex (`usize::MAX` for fixed ones).
    row: Vec<usize>,
    /// The lower-triangle entries: the diagonal of each free vertex, then one per spring
    /// between free vertices (`(row, col, spring)`).
    offdiag: Vec<(usize, usize, u32)>,
    factors: Vec<linalg::spd::SpdFactor>,
    /// CG iterations of the first solve after the last factorization (`None`: refactor now).
    baseline: Option<usize>,
    /// Whether the last CG asks for new factors.
    stale: bool,
    /// Numeric factorizations so far.
    pub factorizations: usize,
    /// One axis's right-hand side in free-vertex order (the solve's workspace).
    rhs: std::sync::Mutex<Mat<f64>>,
}

/// Below this many CG iterations the factors are kept however they compare.
const REFACTOR_MIN_ITERS: usize = 8;

impl AxisLaplacians {
    fn new(start: &[usize], adj: &[(u32, u32)], free: &[bool]) -> AxisLaplacians {
        let mut row = vec![usize::MAX; free.len()];
        let mut n = 0;
        for (v, &f) in free.iter().enumerate() {
            if f {
                row[v] = n;
                n += 1;
            }
        }
        let mut offdiag = Vec::new();
        for v in 0..free.len() {
            for &(u, s) in &adj[start[v]..start[v + 1]] {
                let (rv, ru) = (row[v], row[u as usize]);
                if rv != usize::MAX && ru != usize::MAX && rv > ru {
                    offdiag.push((rv, ru, s));
                }
            }
        }
        AxisLaplacians {
            row,
            offdiag,
            factors: Vec::new(),
            baseline: None,
            stale: true,
            factorizations: 0,
            rhs: std::sync::Mutex::new(Mat::zeros(n, 1)),
        }
    }

    /// Refactors from the current blocks when the factors are stale (`start` and `adj`: the
    /// springs around each vertex, as `HessianPcg` keeps them).
    fn update(
        &mut self,
        start: &[usize],
        adj: &[(u32, u32)],
        blocks: &[Sym3],
        diag: &[Sym3],
    ) -> Result<(), PcgError> {
        if !self.stale && !self.factors.is_empty() {
            return Ok(());
        }
        let n = self.rhs.lock().unwrap_or_else(|e| e.into_inner()).nrows();
        // The aa entry of a Sym3 (xx, xy, xz, yy, yz, zz).
        const AA: [usize; 3] = [0, 3, 5];
        for (a, &aa) in AA.iter().enumerate() {
            let mut d = vec![0.0; n];
            for (v, &r) in self.row.iter().enumerate() {
                if r == usize::MAX {
                    continue;
                }
                let mut x = diag[v][aa];
                for &(_, s) in &adj[start[v]..start[v + 1]] {
                    x += blocks[s as usize][aa];
                }
                d[r] = x;
            }
            let trip: Vec<faer::sparse::Triplet<usize, usize, f64>> =
                (0..n)
                    .map(|r| faer::sparse::Triplet::new(r, r, d[r]))
                    .chain(self.offdiag.iter().map(|&(r, c, s)| {
                        faer::sparse::Triplet::new(r, c, -blocks[s as usize][aa])
                    }))
                    .collect();
            match self.factors.get_mut(a) {
                Some(f) => f
                    .refactor(&trip, Par::Seq)
                    .map_err(PcgError::Preconditioner)?,
                None => {
                    let mut f = linalg::spd::SpdFactor::new(n, &trip, Par::Seq)
                        .map_err(PcgError::Preconditioner)?;
                    f.prepare_many_solves();
                    self.factors.push(f);
                }
            }
        }
        self.factorizations += 1;
        self.baseline = None;
        self.stale = false;
        Ok(())
    }

    /// Notes a CG's iteration count; marks the factors stale when they stopped paying.
    fn record(&mut self, iters: usize) {
        match self.baseline {
            None => self.baseline = Some(iters),
            Some(b) => {
                if iters > REFACTOR_MIN_ITERS && iters > 2 * b.max(1) {
                    self.stale = true;
                }
            }
        }
    }
}

impl AxisLaplacians {
    /// `o = P^-1 p` (three entries per vertex, zero at fixed vertices), axis by axis.
    fn solve(&self, p: &[f64], o: &mut [f64]) {
        let mut col = self.rhs.lock().unwrap_or_else(|e| e.into_inner());
        o.fill(0.0);
        for (a, f) in self.factors.iter().enumerate() {
            for (v, &r) in self.row.iter().enumerate() {
                if r != usize::MAX {
                    col[(r, 0)] = p[3 * v + a];
                }
            }
            f.solve_in_place(col.as_mut());
            for (v, &r) in self.row.iter().enumerate() {
                if r != usize::MAX {
                    o[3 * v + a] = col[(r, 0)];
                }
            }
        }
    }
}

#[inline]
fn sym3_mul(b: &Sym3, p: [f64; 3]) -> [f64; 3] {
    [
        b[0] * p[0] + b[1] * p[1] + b[2] * p[2],
        b[1] * p[0] + b[3] * p[1] + b[4] * p[2],
        b[2] * p[0] + b[4] * p[1] + b[5] * p[2],
    ]
}

/// Inverse of a symmetric positive definite 3x3 block by its adjugate (the block is at least
/// `m/h^2 I`, so the determinant is positive).
fn sym3_inverse(b: &Sym3) -> Sym3 {
    let [a, bb, c, d, e, f] = *b;
    let c00 = d * f - e * e;
    let c01 = c * e - bb * f;
    let c02 = bb * e - c * d;
    let det = a * c00 + bb * c01 + c * c02;
    [
        c00 / det,
        c01 / det,
        c02 / det,
        (a * f - c * c) / det,
        (bb * c - a * e) / det,
        (a * d - bb * bb) / det,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn block_inverse_times_block_is_identity() {
        let b = [4.0, 1.0, 0.5, 3.0, -0.25, 2.0];
        let inv = sym3_inverse(&b);
        for (k, e) in [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
            .into_iter()
            .enumerate()
        {
            let r = sym3_mul(&b, sym3_mul(&inv, e));
            for a in 0..3 {
                let want = if a == k { 1.0 } else { 0.0 };
                assert!((r[a] - want).abs() < 1e-14, "{r:?}");
            }
        }
    }
}
