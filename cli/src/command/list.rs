//! `svi list`: the built-in scenes and the models with their parameters.

use serde::Serialize;
use svi_models::{MODEL_NAMES, ModelVisitor, ZooModel, visit_model};

use crate::report::csv::Float;
use crate::report::summary::Parameters;
use crate::scene::builtin::BUILTIN_SCENES;

/// A zoo model's name, dimension, coordinates, parameters and defaults (for `svi list`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ModelDescription {
    /// Name.
    pub name: &'static str,
    /// Configuration coordinate names.
    pub coordinates: Vec<&'static str>,
    /// Default parameters.
    pub parameters: Parameters,
    /// Default step.
    pub h: f64,
    /// Default horizon.
    pub t_end: f64,
    /// Number of Noether momenta.
    pub momenta: usize,
    /// Whether an exact solution is known for the default initial state.
    pub exact_solution: bool,
}

/// Describes a model.
struct Describe;

impl ModelVisitor for Describe {
    type Output = ModelDescription;

    fn visit<M: ZooModel<N>, const N: usize>(self, model: M) -> ModelDescription {
        let (t0, q0, v0) = model.initial_state();
        ModelDescription {
            name: model.name(),
            coordinates: model.coordinate_names().to_vec(),
            parameters: Parameters(model.parameters()),
            h: model.default_step(),
            t_end: model.default_horizon(),
            momenta: model.generator_count(),
            exact_solution: model.exact_solution(t0, &q0, &v0, t0).is_some(),
        }
    }
}

/// Descriptions of all zoo models, in [`MODEL_NAMES`] order.
pub fn describe_models() -> Vec<ModelDescription> {
    MODEL_NAMES
        .iter()
        .filter_map(|name| visit_model(name, Describe).ok())
        .collect()
}

/// Print the built-in scenes and the models (vector and rigid-body) with their parameters.
pub fn print() {
    println!("Built-in scenes (svi run NAME):");
    let width = BUILTIN_SCENES
        .iter()
        .map(|(name, _)| name.len() + 2)
        .max()
        .unwrap_or(0)
        .max(18);
    for (name, text) in BUILTIN_SCENES {
        let description = text
            .lines()
            .next()
            .and_then(|line| line.strip_prefix('#'))
            .unwrap_or("")
            .trim();
        println!("  {name:<width$}{description}");
    }
    println!();
    println!("Models (model = \"NAME\" in a scene; parameters, default step and horizon):");
    for model in describe_models() {
        let parameters: Vec<String> = model
            .parameters
            .0
            .iter()
            .map(|(name, value)| format!("{name} = {}", Float(*value)))
            .collect();
        let mut facts = vec![format!("q = ({})", model.coordinates.join(", "))];
        if model.momenta > 0 {
            let noun = if model.momenta == 1 {
                "momentum"
            } else {
                "momenta"
            };
            facts.push(format!("{} Noether {noun}", model.momenta));
        }
        if model.exact_solution {
            facts.push("exact solution".into());
        }
        println!(
            "  {:<18}{}; h = {}, t_end = {}; {}",
            model.name,
            parameters.join(", "),
            Float(model.h),
            Float(model.t_end),
            facts.join(", ")
        );
    }
    println!();
    for line in crate::rigid::list_lines() {
        println!("{line}");
    }
}
