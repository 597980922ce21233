//! The integration tests, one binary (`cargo test --release --test it`): one module per
//! domain or runtime part, sharing the helpers in `common` and `support`. A single binary
//! links once, where one binary per file linked the whole crate a dozen times.

mod common;
mod support;

mod anim;
mod animation;
mod arap;
mod cache_semantics;
mod cli_help;
mod course_graphs;
mod curve;
mod defaults;
mod f3d;
mod f3d_map;
mod f3d_project;
mod gbuffer;
mod graphs;
mod hostile;
mod image_lowrank;
mod image_warp;
mod layout;
mod learn;
mod loader_bounds;
mod mass_spring;
mod mass_spring_node;
mod mesh;
mod node_bounds;
mod param;
mod plugins;
mod poisson;
mod progress;
mod provenance;
mod render;
mod report;
mod run_semantics;
mod runtime;
mod schema;
mod serve;
mod shard;
mod sph;
mod sweep;
mod trace;
mod trace_shading;
