//! Curves and data fitting (GAMES102 homework 1-2, the modeling course's third assignment):
//! parameterizing a sequence of points, interpolating it by polynomial, cubic spline, RBF and
//! Bézier curves, fitting functions to data by least squares. One algorithm per file
//! (`barycentric`, `cubic_spline`, `rbf`, `bezier`, `lstsq`), the nodes beside them.

pub mod barycentric;
pub mod bezier;
pub mod cubic_spline;
pub mod curve_interpolate;
pub mod curve_mlp;
pub mod curve_parameterize;
pub mod data_fit;
pub mod lstsq;
pub mod plot;
pub mod rbf;

use cgnodes_api::registry::Registry;

/// Registers this family's nodes, in the `curve` category.
pub fn register(r: &mut Registry) {
    r.with_category("curve", |r| {
        curve_interpolate::register(r);
        curve_parameterize::register(r);
        data_fit::register(r);
        plot::register(r);
    });
}
