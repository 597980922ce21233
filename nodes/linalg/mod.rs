//! Linear-algebra building blocks shared by node families (parameterization, simulation):
//! thin wrappers over faer that keep a factorization and its scratch memory together.

pub mod spd;
pub mod two_domain;

pub use spd::SpdFactor;
pub use two_domain::TwoDomainFactor;
