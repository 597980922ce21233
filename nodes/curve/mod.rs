//! Curves and data fitting (GAMES102 homework 1-2, the modeling course's third assignment):
//! parameterizing a sequence of points, interpolating it by polynomial, cubic spline, RBF and
//! Bézier curves, fitting functions to data by least squares. One algorithm per file
//! (`barycentric`, `cubic_spline`, `rbf`, `bezier`, `lstsq`), the nodes beside them.

crate::node_domain! {
    category: "curve",
    nodes: [curve_interpolate, curve_parameterize, data_fit, plot],
    modules: [barycentric, bezier, cubic_spline, curve_mlp, lstsq, rbf],
}
