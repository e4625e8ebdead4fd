//! `svi list`: the built-in scenes and the models with their parameters, on ℝᴺ (fixed N and
//! runtime dimension) and on SO(3), and the Lie groups of the registry
//! ([`svi::model::group::registry::GROUPS`]).

use nalgebra::DefaultAllocator;
use nalgebra::allocator::Allocator;
use serde::Serialize;
use svi::Dimension;
use svi::method::registry::SpaceKind;
use svi::model::group::registry::GROUPS;
use svi_models::{
    GROUP_MODEL_NAMES, GroupModelVisitor, GroupZooModel, LOCAL_MODEL_NAMES, LocalModelVisitor,
    LocalZooModel, MODEL_NAMES, ModelVisitor, RIGID_MODEL_NAMES, RigidModelVisitor, RigidZooModel,
    ZooModel, visit_group_model, visit_local_model, visit_model, visit_rigid_model,
};

use crate::report::csv::Float;
use crate::report::summary::Parameters;
use crate::run::methods_of_any_size;
use crate::scene::Scene;
use crate::scene::builtin::BUILTIN_SCENES;
use crate::scene::field::FIELD_SCENES;
use crate::scene::spectral::SPECTRAL_SCENES;

/// A zoo model's name, dimension, coordinates, parameters and defaults (for `svi list`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ModelDescription {
    /// Name.
    pub name: &'static str,
    /// Configuration coordinate names.
    pub coordinates: Vec<String>,
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

    fn visit<M: ZooModel<N>, N: Dimension>(self, model: M) -> ModelDescription
    where
        DefaultAllocator: Allocator<N> + Allocator<N, N>,
    {
        let (t0, q0, v0) = model.initial_state();
        ModelDescription {
            name: model.name(),
            coordinates: model.coordinate_names(),
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

/// The built-in scenes on `space` whose model is (`local`) or is not of runtime dimension,
/// as (name, the first line of the scene file).
fn scenes(space: SpaceKind, local: bool) -> Vec<(&'static str, &'static str)> {
    BUILTIN_SCENES
        .iter()
        .filter(|(name, _)| {
            Scene::builtin(name).is_some_and(|scene| {
                scene.is_ok_and(|s| s.space() == space && s.is_local() == local)
            })
        })
        .map(|(name, text)| (*name, description(text)))
        .collect()
}

/// A scene's description: the first line of its file, a `#` comment.
fn description(text: &str) -> &str {
    text.lines()
        .next()
        .and_then(|line| line.strip_prefix('#'))
        .unwrap_or("")
        .trim()
}

/// The width of the name column of the listing: the longest model name and two spaces.
const NAME_COLUMN: usize = 23;

/// The listing of `svi list`: the built-in scenes and the models (on ℝᴺ, chains of runtime
/// dimension and rigid bodies) with their parameters, and the registered Lie groups.
pub fn listing() -> String {
    let mut out = String::new();
    push_line(&mut out, format_args!("Built-in scenes (svi run NAME):"));
    let vector = scenes(SpaceKind::Vector, false);
    let width = vector
        .iter()
        .map(|(name, _)| name.len() + 2)
        .max()
        .unwrap_or(0)
        .max(NAME_COLUMN);
    for (name, description) in vector {
        push_line(&mut out, format_args!("  {name:<width$}{description}"));
    }
    out.push('\n');
    push_line(
        &mut out,
        format_args!("Models (model = \"NAME\" in a scene; parameters, default step and horizon):"),
    );
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
        push_line(
            &mut out,
            format_args!(
                "  {:<NAME_COLUMN$}{}; h = {}, t_end = {}; {}",
                model.name,
                parameters.join(", "),
                Float(model.h),
                Float(model.t_end),
                facts.join(", ")
            ),
        );
    }
    out.push('\n');
    push_line(
        &mut out,
        format_args!(
            "Chains and lattices of any size n (svi run NAME --param n=N; every method while its \
         dense matrices fit, at any n those each model below lists):"
        ),
    );
    for (name, description) in scenes(SpaceKind::Vector, true) {
        push_line(
            &mut out,
            format_args!("  {name:<NAME_COLUMN$}{description}"),
        );
    }
    out.push('\n');
    push_line(
        &mut out,
        format_args!(
            "Runtime-dimension models (model = \"NAME\"; parameters, default step and horizon; \
         trajectory columns t, energy and these observables):"
        ),
    );
    for name in LOCAL_MODEL_NAMES {
        if let Some(line) = visit_local_model(name, DescribeLocal) {
            push_line(&mut out, format_args!("{line}"));
        }
    }
    out.push('\n');
    push_line(
        &mut out,
        format_args!("Scenes on Lie groups (svi run NAME; method lie-svi):"),
    );
    for (name, description) in scenes(SpaceKind::Group, false) {
        push_line(
            &mut out,
            format_args!("  {name:<NAME_COLUMN$}{description}"),
        );
    }
    out.push('\n');
    push_line(
        &mut out,
        format_args!("Rigid-body models (model = \"NAME\"; parameters, default step and horizon):"),
    );
    for name in RIGID_MODEL_NAMES {
        if let Some(line) = visit_rigid_model(name, DescribeRigid) {
            push_line(&mut out, format_args!("{line}"));
        }
    }
    out.push('\n');
    push_line(
        &mut out,
        format_args!(
            "Models on other Lie groups (model = \"NAME\"; [initial] g or log, xi or momentum; \
         parameters, default step and horizon):"
        ),
    );
    for name in GROUP_MODEL_NAMES {
        if let Some(line) = visit_group_model(name, DescribeGroup) {
            push_line(&mut out, format_args!("{line}"));
        }
    }
    out.push('\n');
    push_line(
        &mut out,
        format_args!(
            "Lie groups for models written in Rust (svi::model::group::registry::GROUPS; \
         dimension N, stored numbers E):"
        ),
    );
    for group in GROUPS {
        push_line(
            &mut out,
            format_args!(
                "  {:<NAME_COLUMN$}N = {}, E = {}; {}",
                group.name, group.dimension, group.stored, group.summary
            ),
        );
    }
    out.push('\n');
    push_line(
        &mut out,
        format_args!(
            "Field scenes in 1 + 1 dimensions (svi run NAME --param points=N; the multisymplectic \
         integrator, on a moving mesh where the scene names a monitor; each runs the model its \
         name begins with):"
        ),
    );
    for (name, text) in FIELD_SCENES {
        push_line(&mut out, format_args!("  {name:<22}{}", description(text)));
    }
    out.push('\n');
    push_line(
        &mut out,
        format_args!(
            "Pseudospectral scenes, complex fields (svi run NAME --method midpoint|svi:P \
         --param points=N):"
        ),
    );
    for (name, text) in SPECTRAL_SCENES {
        push_line(&mut out, format_args!("  {name:<22}{}", description(text)));
    }
    out
}

/// Append `text` and a newline to `out`.
fn push_line(out: &mut String, text: std::fmt::Arguments<'_>) {
    use std::fmt::Write;
    let _ = writeln!(out, "{text}");
}

/// Describes a runtime-dimension model in one line.
struct DescribeLocal;

impl LocalModelVisitor for DescribeLocal {
    type Output = String;
    fn visit<M: LocalZooModel>(self, model: M) -> String {
        let parameters: Vec<String> = model
            .parameters()
            .iter()
            .map(|(name, value)| format!("{name} = {}", Float(*value)))
            .collect();
        let mut facts = vec![format!(
            "observables {}",
            model.observable_names().join(", ")
        )];
        let invariants: Vec<&str> = (0..model.invariant_count())
            .map(|i| model.invariant_name(i))
            .collect();
        if !invariants.is_empty() {
            facts.push(format!("conserves {}", invariants.join(", ")));
        }
        let (name, h, t_end) = (model.name(), model.default_step(), model.default_horizon());
        facts.push(format!(
            "methods at any n: {}",
            methods_of_any_size(model.into()).join(", ")
        ));
        format!(
            "  {:<NAME_COLUMN$}{}; h = {}, t_end = {}; {}",
            name,
            parameters.join(", "),
            Float(h),
            Float(t_end),
            facts.join("; ")
        )
    }
}

/// Describes a rigid-body model in one line.
struct DescribeRigid;

impl RigidModelVisitor for DescribeRigid {
    type Output = String;
    fn visit<M: RigidZooModel>(self, model: M) -> String {
        let mut facts = Vec::new();
        if M::G_INVARIANT {
            facts.push("G-invariant".to_string());
        }
        let momenta: Vec<&str> = (0..model.axis_count())
            .map(|i| model.axis_name(i))
            .collect();
        if !momenta.is_empty() {
            facts.push(format!("conserves {}", momenta.join(", ")));
        }
        group_line(
            model.name(),
            &model.parameters(),
            (model.default_step(), model.default_horizon()),
            facts,
        )
    }
}

/// Describes a model on another Lie group in one line.
struct DescribeGroup;

impl GroupModelVisitor for DescribeGroup {
    type Output = String;
    fn visit<M: GroupZooModel<N, E>, const N: usize, const E: usize>(self, model: M) -> String {
        let mut facts = vec![format!("group dimension {N}, stored as {E} numbers")];
        if M::G_INVARIANT {
            facts.push("G-invariant".to_string());
        }
        let momenta: Vec<&str> = (0..model.generator_count())
            .map(|i| model.momentum_name(i))
            .collect();
        if !momenta.is_empty() {
            facts.push(format!("conserves {}", momenta.join(", ")));
        }
        let (g0, xi0) = model.initial_state();
        if model.exact_solution(&g0, &xi0, 0.0).is_some() {
            facts.push("exact solution".into());
        }
        group_line(
            model.name(),
            &model.parameters(),
            (model.default_step(), model.default_horizon()),
            facts,
        )
    }
}

/// One line of a model on a Lie group: name, parameters, default step and horizon, facts.
fn group_line(
    name: &str,
    parameters: &[(&'static str, f64)],
    (h, t_end): (f64, f64),
    facts: Vec<String>,
) -> String {
    let parameters: Vec<String> = parameters
        .iter()
        .map(|(name, value)| format!("{name} = {}", Float(*value)))
        .collect();
    format!(
        "  {:<NAME_COLUMN$}{}; h = {}, t_end = {}; {}",
        name,
        parameters.join(", "),
        Float(h),
        Float(t_end),
        facts.join(", ")
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_listing_shows_every_registered_group() {
        let text = listing();
        assert!(
            text.contains("Lie groups for models written in Rust"),
            "{text}"
        );
        for group in GROUPS {
            let line = format!(
                "  {:<NAME_COLUMN$}N = {}, E = {}; {}\n",
                group.name, group.dimension, group.stored, group.summary
            );
            assert!(text.contains(&line), "{line}: {text}");
        }
        assert!(
            text.contains("SE(3)") && text.contains("N = 6, E = 12"),
            "{text}"
        );
    }
}
