//! Field scenes: a 1 + 1 field theory of the zoo ([`svi_models::FIELD_MODEL_NAMES`]) run by
//! the multisymplectic integrator ([`svi::field`]). They have their own, smaller format and
//! their own run path (`run/field.rs`): a field has a mesh instead of an initial state
//! and a method.
//!
//! ```toml
//! # The sine-Gordon breather (the first line, a comment, describes the scene)
//! model = "sine-gordon-breather"
//!
//! [parameters]            # model parameters (absent: the model's defaults)
//! omega = 0.5
//!
//! [mesh]
//! points = 401            # nodes in space (absent: the model's default)
//! quadrature = "trapezoid"   # cell quadrature: "trapezoid" (explicit for ½u_t² − …,
//!                            # the default) or "midpoint" (the implicit box scheme)
//!
//! [run]                   # absent: the model's default step and horizon
//! h = 0.05                # the time step Δt
//! t_end = 50.0            # the run ends at the first level at or after it
//!
//! [output]
//! trajectory = "breather.csv"   # the field as CSV, rows t,x,u (absent: none)
//! every = 10                    # every 10th time level (default 1)
//! # plot = "breather.svg"       # a space-time picture of that file (needs trajectory)
//! multisymplectic_check = true  # measure the discrete multisymplectic law (default true)
//! ```
//!
//! From the command line, `--h`, `--t-end`, `--param NAME=VALUE` (`--param points=N` sets
//! the mesh), `--out`, `--every` and `--plot` apply; every other run flag is an error
//! ([`SceneError::NotApplicable`]).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::Deserialize;
use serde::de::DeserializeOwned;
use svi::field::multisymplectic::CellQuadrature;
use svi_models::FIELD_MODEL_NAMES;

use crate::scene::error::SceneError;
use crate::scene::limits::read_scene_file;
use crate::scene::overrides::Overrides;
use crate::scene::set;

/// The built-in field scenes, as (name, TOML text).
pub const FIELD_SCENES: &[(&str, &str)] = &[
    ("wave", include_str!("../../scenes/wave.toml")),
    (
        "sine-gordon-kink",
        include_str!("../../scenes/sine-gordon-kink.toml"),
    ),
    (
        "sine-gordon-breather",
        include_str!("../../scenes/sine-gordon-breather.toml"),
    ),
    ("phi4-kink", include_str!("../../scenes/phi4-kink.toml")),
];

/// A field scene (see the module documentation).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FieldScene {
    /// The field model, one of [`FIELD_MODEL_NAMES`].
    pub model: String,
    /// Model parameters, name → value.
    #[serde(default)]
    pub parameters: BTreeMap<String, f64>,
    /// The mesh.
    #[serde(default)]
    pub mesh: MeshSection,
    /// Step and horizon.
    #[serde(default)]
    pub run: FieldRunSection,
    /// Outputs.
    #[serde(default)]
    pub output: FieldOutputSection,
    /// The scene file it was read from (none for a built-in scene): no output may be
    /// written over it. Not a scene field.
    #[serde(skip)]
    pub source: Option<PathBuf>,
}

/// `[mesh]` of a field scene.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeshSection {
    /// Nodes in space.
    pub points: Option<usize>,
    /// The cell quadrature.
    pub quadrature: Option<QuadratureName>,
}

/// The cell quadrature as a scene names it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum QuadratureName {
    /// [`CellQuadrature::Trapezoid`].
    Trapezoid,
    /// [`CellQuadrature::Midpoint`].
    Midpoint,
}

impl QuadratureName {
    /// The library's quadrature.
    pub fn quadrature(self) -> CellQuadrature {
        match self {
            QuadratureName::Trapezoid => CellQuadrature::Trapezoid,
            QuadratureName::Midpoint => CellQuadrature::Midpoint,
        }
    }
}

/// `[run]` of a field scene.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FieldRunSection {
    /// The time step Δt.
    pub h: Option<f64>,
    /// The final time (the run ends at the first level at or after it).
    pub t_end: Option<f64>,
}

/// `[output]` of a field scene.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FieldOutputSection {
    /// The CSV file of the field (rows `t,x,u`).
    pub trajectory: Option<PathBuf>,
    /// Write every k-th time level.
    pub every: Option<usize>,
    /// An SVG space-time picture of the field written to `trajectory` (needs it).
    pub plot: Option<PathBuf>,
    /// Measure the discrete multisymplectic conservation law (default true).
    pub multisymplectic_check: Option<bool>,
}

impl FieldScene {
    /// The field scene `name_or_path` names: a built-in field scene, or a scene file whose
    /// `model` is a field model; `None` for anything else (the other scenes, and paths that
    /// are no readable file: the scene loader reports those).
    pub fn load(name_or_path: &str) -> Option<Result<FieldScene, SceneError>> {
        let loaded = load_space_time(name_or_path, FIELD_SCENES, FIELD_MODEL_NAMES)?;
        Some(loaded.map(|(scene, source)| FieldScene { source, ..scene }))
    }

    /// Put the command-line flags on top: `--h`, `--t-end`, `--param` (`points` sets
    /// `mesh.points`), `--out`, `--every` and `--plot`; any other run flag is
    /// [`SceneError::NotApplicable`].
    pub fn apply(&mut self, overrides: &Overrides) -> Result<(), SceneError> {
        reject_other_flags(overrides, false, || {
            format!(
                "'{}' is a field scene (the multisymplectic integrator): it takes --h, \
                 --t-end, --param (points=N for the mesh), --out, --every and --plot",
                self.model
            )
        })?;
        SpaceTimeFields {
            parameters: &mut self.parameters,
            points: &mut self.mesh.points,
            run: &mut self.run,
            trajectory: &mut self.output.trajectory,
            every: &mut self.output.every,
            plot: &mut self.output.plot,
            source: self.source.as_deref(),
        }
        .apply(overrides, "mesh points")
    }
}

/// The space–time scene `name_or_path` names, with the path of its file: one of the
/// built-in `scenes` (name, TOML text), or a scene file whose `model` is one of `models`;
/// `None` for anything else (the other scenes, and paths that are no readable file: the
/// scene loader reports those).
pub fn load_space_time<S: DeserializeOwned>(
    name_or_path: &str,
    scenes: &[(&str, &str)],
    models: &[&str],
) -> Option<Result<(S, Option<PathBuf>), SceneError>> {
    if let Some((name, text)) = scenes.iter().find(|(name, _)| *name == name_or_path) {
        return Some(from_toml(text, &format!("built-in scene '{name}'")).map(|s| (s, None)));
    }
    let path = Path::new(name_or_path);
    let text = read_scene_file(path).ok()?;
    let table: toml::Table = toml::from_str(&text).ok()?;
    let model = table.get("model")?.as_str()?;
    models
        .contains(&model)
        .then(|| from_toml(&text, &format!("'{}'", path.display())).map(|s| (s, Some(path.into()))))
}

/// Parse a scene of type `S`; `origin` names the source in error messages.
fn from_toml<S: DeserializeOwned>(text: &str, origin: &str) -> Result<S, SceneError> {
    toml::from_str(text).map_err(|parser| SceneError::Parse {
        origin: origin.into(),
        parser,
    })
}

/// The first flag of `svi run` that a space–time scene (a field scene, a pseudospectral one)
/// does not take, as [`SceneError::NotApplicable`] with `reason`: every flag but those
/// [`SpaceTimeFields::apply`] reads, and `--method` where `takes_method`.
pub fn reject_other_flags(
    overrides: &Overrides,
    takes_method: bool,
    reason: impl FnOnce() -> String,
) -> Result<(), SceneError> {
    let unused = [
        (overrides.run.method.is_some() && !takes_method, "--method"),
        (overrides.run.points.is_some(), "--points"),
        (overrides.run.quadrature.is_some(), "--quadrature"),
        (overrides.run.diagnostics.is_some(), "--diagnostics"),
        (overrides.run.adapt.is_some(), "--adapt"),
        (overrides.run.tol.is_some(), "--tol"),
        (overrides.run.monitor.is_some(), "--monitor"),
        (overrides.output_times.is_some(), "--output-times"),
        (overrides.run.recovery.is_some(), "--recovery"),
        (
            overrides.run.divergence_limit.is_some(),
            "--divergence-limit",
        ),
        (overrides.run.max_steps.is_some(), "--max-steps"),
        (overrides.run.form.is_some(), "--form"),
    ];
    match unused.into_iter().find(|(given, _)| *given) {
        Some((_, option)) => Err(SceneError::NotApplicable {
            option,
            reason: reason(),
        }),
        None => Ok(()),
    }
}

/// The fields of a space–time scene that the command-line flags set.
pub struct SpaceTimeFields<'a> {
    /// Model parameters.
    pub parameters: &'a mut BTreeMap<String, f64>,
    /// The nodes in space (`--param points=N`).
    pub points: &'a mut Option<usize>,
    /// Step and horizon.
    pub run: &'a mut FieldRunSection,
    /// The CSV file of the field.
    pub trajectory: &'a mut Option<PathBuf>,
    /// Write every k-th time level.
    pub every: &'a mut Option<usize>,
    /// The space-time picture.
    pub plot: &'a mut Option<PathBuf>,
    /// The scene file, which no output may overwrite.
    pub source: Option<&'a Path>,
}

impl SpaceTimeFields<'_> {
    /// Put `--param` (`points` a whole number of `unit`), `--h`, `--t-end`, `--out`, `--every`
    /// and `--plot` on top, then check the outputs: a plot and `every` need the trajectory,
    /// `every` is positive.
    pub fn apply(self, overrides: &Overrides, unit: &str) -> Result<(), SceneError> {
        for (name, value) in &overrides.parameters {
            if name == "points" {
                if value.fract() != 0.0 || *value < 0.0 || *value > usize::MAX as f64 {
                    return Err(SceneError::InvalidOption {
                        option: "points",
                        reason: format!("{value:?} is not a whole number of {unit}"),
                    });
                }
                *self.points = Some(*value as usize);
            } else {
                self.parameters.insert(name.clone(), *value);
            }
        }
        set(&mut self.run.h, &overrides.run.h);
        set(&mut self.run.t_end, &overrides.run.t_end);
        set(self.every, &overrides.every);
        set(self.trajectory, &overrides.out);
        set(self.plot, &overrides.plot);
        if self.plot.is_some() && self.trajectory.is_none() {
            return Err(SceneError::NotApplicable {
                option: "--plot (output.plot)",
                reason: "draws the field written to the trajectory file: give --out FILE \
                         (output.trajectory) too"
                    .into(),
            });
        }
        if self.every.is_some() && self.trajectory.is_none() {
            return Err(SceneError::EveryWithoutOutput);
        }
        if *self.every == Some(0) {
            return Err(SceneError::InvalidOption {
                option: "every",
                reason: "0; need a positive number of time levels".into(),
            });
        }
        Ok(crate::report::output::check_run_outputs(
            self.trajectory.as_deref(),
            self.plot.as_deref(),
            None,
            self.source,
        )?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::overrides::RunFlags;

    #[test]
    fn the_built_in_field_scenes_parse_and_name_field_models() {
        for (name, _) in FIELD_SCENES {
            let scene = FieldScene::load(name).unwrap().unwrap();
            assert!(FIELD_MODEL_NAMES.contains(&scene.model.as_str()), "{name}");
        }
        assert!(FieldScene::load("kepler").is_none());
    }

    #[test]
    fn flags_for_other_scenes_are_not_applicable() {
        let mut scene = FieldScene::load("wave").unwrap().unwrap();
        let overrides = Overrides {
            run: RunFlags {
                adapt: Some(crate::scene::schema::AdaptMode::Step),
                ..RunFlags::default()
            },
            ..Overrides::default()
        };
        assert!(matches!(
            scene.apply(&overrides),
            Err(SceneError::NotApplicable {
                option: "--adapt",
                ..
            })
        ));
        let overrides = Overrides {
            run: RunFlags {
                h: Some(0.01),
                ..RunFlags::default()
            },
            parameters: vec![("points".into(), 64.0), ("c".into(), 2.0)],
            ..Overrides::default()
        };
        scene.apply(&overrides).unwrap();
        assert_eq!(scene.mesh.points, Some(64));
        assert_eq!(scene.parameters.get("c"), Some(&2.0));
        assert_eq!(scene.run.h, Some(0.01));
        let overrides = Overrides {
            parameters: vec![("points".into(), 6.5)],
            ..Overrides::default()
        };
        assert!(scene.apply(&overrides).is_err());
    }
}
