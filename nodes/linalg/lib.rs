//! Linear-algebra building blocks shared by node families (parameterization, simulation,
//! image editing): thin wrappers over faer that keep a factorization and its scratch memory
//! together, fill-reducing orders, and Dirichlet solves of graph Laplacians.

pub mod laplace;
pub mod laplace_weights;
pub mod nested_dissection;
pub mod spd;
pub mod two_domain;

pub use laplace::{DirichletFactor, LaplaceRows};
pub use nested_dissection::Dissection;
pub use spd::SpdFactor;
pub use two_domain::TwoDomainFactor;
