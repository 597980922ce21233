//! Test harnesses shared by several test modules (and, for the dam break, by `bench/sph.rs`).

pub mod browser;
pub mod hanging_cloth;
pub mod sph_dam_break;
