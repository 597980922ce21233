//! `model_save` and `model_load`: a trained classifier as JSON (the `Model` value's fields:
//! kind, activation, layers with row-major weights, features, label, classes, mean, scale).

use super::dataset::{network, ModelError};
use cgnodes_api::prelude::*;
use std::path::Path;

fn declare_save(b: &mut NodeBuilder) {
    b.doc("Writes a trained model as JSON.");
    b.sink();
    b.add_input::<Model>("model");
    b.add_input::<String>("path")
        .file_out()
        .doc("Output file (.json), under the output directory.");
}

fn execute_save(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let m: Arc<Model> = ctx.input("model")?;
    let p: String = ctx.input("path")?;
    let path = ctx.output_path("path", &p)?;
    if path.extension().and_then(|e| e.to_str()) != Some("json") {
        return Err(NodeError::invalid(
            "path",
            format!("'{p}' should end in .json"),
        ));
    }
    let text = serde_json::to_string_pretty(&*m)
        .map_err(|e| NodeError::invalid("model", e.to_string()))?;
    ctx.write_file(&path, text.as_bytes())
}

fn declare_load(b: &mut NodeBuilder) {
    b.doc("Reads a model written by model_save.");
    b.add_input::<String>("path")
        .file_in()
        .doc("A .json model file.");
    b.add_output::<Model>("model");
}

/// Why a model file's text is not a model.
#[derive(Debug, thiserror::Error)]
pub enum ModelFileError {
    /// Not JSON of the `Model` shape.
    #[error("{0}")]
    Json(#[from] serde_json::Error),
    /// JSON of the right shape whose network does not fit together.
    #[error("{0}")]
    Network(#[from] ModelError),
}

/// Parses and checks a model's JSON text.
pub fn parse_model(text: &str) -> Result<Model, ModelFileError> {
    let m: Model = serde_json::from_str(text)?;
    network(&m)?;
    Ok(m)
}

fn execute_load(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let p: String = ctx.input("path")?;
    let path = ctx.input_path(&p);
    let text = std::fs::read_to_string(&path).map_err(|e| NodeError::io(&path, e).at("path"))?;
    let m = parse_model(&text).map_err(|e| {
        let e = if ctx.files().is_within_run_folders(&path) {
            e.to_string()
        } else {
            "not a cgnodes model file".into()
        };
        NodeError::invalid("path", format!("{}: {e}", Path::new(&p).display()))
    })?;
    ctx.set_output("model", m);
    Ok(())
}

/// Registers `model_save` and `model_load`.
pub fn register(r: &mut Registry) {
    r.add("model_save", declare_save, execute_save);
    r.add("model_load", declare_load, execute_load);
}
