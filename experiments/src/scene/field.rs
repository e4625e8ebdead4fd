//! Field scenes: a 1 + 1 field theory of the zoo ([`svi_models::FIELD_MODEL_NAMES`]) run by
//! the multisymplectic integrator ([`svi::field`]) on a uniform mesh, or by the r-adaptive
//! (moving-mesh) one ([`svi::field::r_adaptive`]) when `[mesh]` names a `monitor`. They have
//! their own, smaller format and their own run path (`run/field.rs`): a field has a mesh
//! instead of an initial state and a method.
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
//! # Moving meshes
//! A `monitor` in `[mesh]` makes the nodes move with the field (the r-adaptive integrator;
//! Dirichlet models only, whose density does not depend on x explicitly):
//!
//! ```toml
//! [mesh]
//! points = 101              # nodes, the ends held at the domain's ends
//! monitor = "arc-length"    # ω = √(1 + α|u_x|²); or "curvature": √(1 + α|u_x|² + β|u_xx|²)
//! monitor_scale = 4.0       # α ≥ 0 (default 1)
//! # monitor_curvature = 1.0 # β ≥ 0, only with "curvature" (default 1)
//! smoothing = 2.0           # κ ≥ 0: neighbouring cells within the ratio (κ + 1)/κ (default 2)
//! quadrature = "midpoint"   # the default on a moving mesh; "trapezoid" is the leapfrog
//! ```
//!
//! `monitor_scale`, `monitor_curvature` or `smoothing` without `monitor`, and
//! `monitor_curvature` with `"arc-length"`, are errors ([`SceneError::NotApplicable`]). The
//! field CSV of a moving mesh has rows `t,x,u,node` (the node's index: its path x_i(t)), its
//! plot draws the node paths over the field, and `output.multisymplectic_check` is an error
//! there (the law holds in computational variables; it is not measured).
//!
//! From the command line, `--h`, `--t-end`, `--param NAME=VALUE` (`--param points=N` sets
//! the mesh; on a moving mesh also `smoothing=K`, `monitor_scale=A` and
//! `monitor_curvature=B`), `--out`, `--every` and `--plot` apply; every other run flag is an
//! error ([`SceneError::NotApplicable`]).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::Deserialize;
use serde::de::DeserializeOwned;
use svi::field::multisymplectic::CellQuadrature;
use svi::field::r_adaptive::Monitor;
use svi_models::FIELD_MODEL_NAMES;

use crate::scene::error::SceneError;
use crate::scene::limits::read_scene_file;
use crate::scene::overrides::{Overrides, RunFlags};
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
    (
        "sine-gordon-kink-fast",
        include_str!("../../scenes/sine-gordon-kink-fast.toml"),
    ),
    (
        "phi4-kink-moving-mesh",
        include_str!("../../scenes/phi4-kink-moving-mesh.toml"),
    ),
    (
        "sine-gordon-kink-antikink",
        include_str!("../../scenes/sine-gordon-kink-antikink.toml"),
    ),
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
    /// The monitor of a moving mesh; absent: the uniform mesh.
    pub monitor: Option<MonitorName>,
    /// α of the monitor (moving mesh only).
    pub monitor_scale: Option<f64>,
    /// β of the curvature monitor (`monitor = "curvature"` only).
    pub monitor_curvature: Option<f64>,
    /// The smoothing κ of the mesh concentration (moving mesh only).
    pub smoothing: Option<f64>,
}

/// The monitor of a moving mesh as a scene names it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MonitorName {
    /// [`Monitor::ArcLength`].
    ArcLength,
    /// [`Monitor::Curvature`].
    Curvature,
}

impl MonitorName {
    /// The name in a scene and in the summary: `arc-length` or `curvature`.
    pub fn name(self) -> &'static str {
        match self {
            MonitorName::ArcLength => "arc-length",
            MonitorName::Curvature => "curvature",
        }
    }
}

/// The moving mesh of a scene's `[mesh]`, its defaults filled in (see
/// [`MeshSection::moving`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MovingMesh {
    /// The monitor as the scene names it.
    pub name: MonitorName,
    /// The library's monitor, with α (and β).
    pub monitor: Monitor,
    /// The smoothing κ.
    pub smoothing: f64,
}

/// The default α of a moving mesh's monitor.
pub const DEFAULT_MONITOR_SCALE: f64 = 1.0;
/// The default β of the curvature monitor.
pub const DEFAULT_MONITOR_CURVATURE: f64 = 1.0;

/// The `[mesh]` keys of a moving mesh only, as the options an error names them by (also set
/// by `--param NAME=VALUE`).
const MOVING_MESH_KEYS: [&str; 3] = [
    "--param monitor_scale (mesh.monitor_scale)",
    "--param monitor_curvature (mesh.monitor_curvature)",
    "--param smoothing (mesh.smoothing)",
];

impl MeshSection {
    /// The moving mesh the section asks for (`None`: the uniform mesh), with the defaults
    /// α = [`DEFAULT_MONITOR_SCALE`], β = [`DEFAULT_MONITOR_CURVATURE`] and the library's κ.
    /// Their values are checked by the integrator ([`svi::Error::InvalidParameter`]).
    ///
    /// # Errors
    /// [`SceneError::NotApplicable`] naming `monitor_scale`, `monitor_curvature` or
    /// `smoothing` given without `monitor`, or `monitor_curvature` with `"arc-length"`.
    pub fn moving(&self) -> Result<Option<MovingMesh>, SceneError> {
        let given = [
            self.monitor_scale.is_some(),
            self.monitor_curvature.is_some(),
            self.smoothing.is_some(),
        ];
        let Some(name) = self.monitor else {
            return match given.iter().position(|given| *given) {
                Some(k) => Err(SceneError::NotApplicable {
                    option: MOVING_MESH_KEYS[k],
                    reason: "sets the moving mesh, and this scene's mesh is uniform: give \
                             [mesh] monitor = \"arc-length\" or \"curvature\" to move it"
                        .into(),
                }),
                None => Ok(None),
            };
        };
        let scale = self.monitor_scale.unwrap_or(DEFAULT_MONITOR_SCALE);
        let monitor = match name {
            MonitorName::ArcLength => {
                if self.monitor_curvature.is_some() {
                    return Err(SceneError::NotApplicable {
                        option: MOVING_MESH_KEYS[1],
                        reason: "weighs u_xx in the curvature monitor, and this scene's monitor \
                                 is \"arc-length\": give monitor = \"curvature\" to use it"
                            .into(),
                    });
                }
                Monitor::ArcLength { scale }
            }
            MonitorName::Curvature => Monitor::Curvature {
                scale,
                curvature: self.monitor_curvature.unwrap_or(DEFAULT_MONITOR_CURVATURE),
            },
        };
        Ok(Some(MovingMesh {
            name,
            monitor,
            smoothing: self
                .smoothing
                .unwrap_or(svi::field::r_adaptive::RAdaptiveOptions::default().smoothing),
        }))
    }

    /// Set the moving-mesh key `name` (one of `monitor_scale`, `monitor_curvature`,
    /// `smoothing`) to `value`; `false` for any other name.
    fn set_moving(&mut self, name: &str, value: f64) -> bool {
        let field = match name {
            "monitor_scale" => &mut self.monitor_scale,
            "monitor_curvature" => &mut self.monitor_curvature,
            "smoothing" => &mut self.smoothing,
            _ => return false,
        };
        *field = Some(value);
        true
    }
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
    /// The CSV file of the field (rows `t,x,u`; `t,x,u,node` on a moving mesh).
    pub trajectory: Option<PathBuf>,
    /// Write every k-th time level.
    pub every: Option<usize>,
    /// An SVG space-time picture of the field written to `trajectory` (needs it).
    pub plot: Option<PathBuf>,
    /// Measure the discrete multisymplectic conservation law (default true; uniform mesh
    /// only).
    pub multisymplectic_check: Option<bool>,
}

impl FieldScene {
    /// The field scene `name_or_path` names: a built-in field scene, or a scene file whose
    /// `model` is a field model; `None` for anything else (the other scenes, and paths that
    /// are no readable file: the scene loader reports those).
    pub fn load(name_or_path: &str) -> Option<Result<FieldScene, SceneError>> {
        let loaded = load_space_time(name_or_path, FIELD_SCENES, FIELD_MODEL_NAMES)?;
        Some(loaded.and_then(|(scene, source)| {
            let scene = FieldScene { source, ..scene };
            scene.moving()?;
            Ok(scene)
        }))
    }

    /// The moving mesh of the scene, if it has one ([`MeshSection::moving`]).
    ///
    /// # Errors
    /// Those of [`MeshSection::moving`], and [`SceneError::NotApplicable`] for
    /// `output.multisymplectic_check` on a moving mesh (the scheme is multisymplectic in the
    /// computational variables, not on the physical mesh: there is no law to measure).
    pub fn moving(&self) -> Result<Option<MovingMesh>, SceneError> {
        let moving = self.mesh.moving()?;
        if moving.is_some() && self.output.multisymplectic_check.is_some() {
            return Err(SceneError::NotApplicable {
                option: "output.multisymplectic_check",
                reason: "measures the discrete multisymplectic law of the uniform mesh; a \
                         moving mesh (mesh.monitor) keeps it in computational variables only, \
                         and it is not measured"
                    .into(),
            });
        }
        Ok(moving)
    }

    /// Put the command-line flags on top: `--h`, `--t-end`, `--param` (`points` sets
    /// `mesh.points`; `smoothing`, `monitor_scale` and `monitor_curvature` set those of a
    /// moving mesh), `--out`, `--every` and `--plot`; any other run flag is
    /// [`SceneError::NotApplicable`], and so is a moving-mesh `--param` on a uniform mesh.
    pub fn apply(&mut self, overrides: &Overrides) -> Result<(), SceneError> {
        reject_other_flags(overrides, false, || {
            format!(
                "'{}' is a field scene (the multisymplectic integrator): it takes --h, \
                 --t-end, --param (points=N for the mesh; smoothing=K, monitor_scale=A and \
                 monitor_curvature=B for a moving mesh), --out, --every and --plot",
                self.model
            )
        })?;
        let mut parameters = Vec::with_capacity(overrides.parameters.len());
        for (name, value) in &overrides.parameters {
            if !self.mesh.set_moving(name, *value) {
                parameters.push((name.clone(), *value));
            }
        }
        self.moving()?;
        let overrides = Overrides {
            parameters,
            ..overrides.clone()
        };
        SpaceTimeFields {
            parameters: &mut self.parameters,
            points: &mut self.mesh.points,
            run: &mut self.run,
            trajectory: &mut self.output.trajectory,
            every: &mut self.output.every,
            plot: &mut self.output.plot,
            source: self.source.as_deref(),
        }
        .apply(&overrides, "mesh points")
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
/// [`SpaceTimeFields::apply`] reads, and `--method` where `takes_method`. The flags are taken
/// apart without a rest pattern, so a flag added to `svi run` does not compile until it is
/// placed here (the chaos indicators, sensitivities, events and sections were once ignored
/// without a word).
pub fn reject_other_flags(
    overrides: &Overrides,
    takes_method: bool,
    reason: impl FnOnce() -> String,
) -> Result<(), SceneError> {
    let Overrides {
        run:
            RunFlags {
                method,
                points,
                quadrature,
                h: _,
                t_end: _,
                diagnostics,
                adapt,
                tol,
                monitor,
                recovery,
                divergence_limit,
                max_steps,
                form,
                indicators,
                sensitivity,
                sensitivity_every,
            },
        parameters: _,
        every: _,
        out: _,
        plot: _,
        output_times,
        multipliers,
        event,
        section,
        events_out,
    } = overrides;
    let unused = [
        (method.is_some() && !takes_method, "--method"),
        (points.is_some(), "--points"),
        (quadrature.is_some(), "--quadrature"),
        (diagnostics.is_some(), "--diagnostics"),
        (adapt.is_some(), "--adapt"),
        (tol.is_some(), "--tol"),
        (monitor.is_some(), "--monitor"),
        (output_times.is_some(), "--output-times"),
        (recovery.is_some(), "--recovery"),
        (divergence_limit.is_some(), "--divergence-limit"),
        (max_steps.is_some(), "--max-steps"),
        (form.is_some(), "--form"),
        (indicators.is_some(), "--indicators"),
        (sensitivity.is_some(), "--sensitivity"),
        (sensitivity_every.is_some(), "--sensitivity-every"),
        (multipliers.is_some(), "--multipliers"),
        (!event.is_empty(), "--event"),
        (section.is_some(), "--section"),
        (events_out.is_some(), "--events-out"),
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

    /// The field scene of `text`, parsed and its moving mesh checked.
    fn parsed(text: &str) -> Result<FieldScene, SceneError> {
        let scene: FieldScene = from_toml(text, "test scene")?;
        scene.moving()?;
        Ok(scene)
    }

    #[test]
    fn a_monitor_makes_the_mesh_move_with_its_keys_or_their_defaults() {
        let uniform = parsed("model = \"phi4-kink\"\n[mesh]\npoints = 81\n").unwrap();
        assert_eq!(uniform.moving().unwrap(), None);
        let plain = parsed("model = \"phi4-kink\"\n[mesh]\nmonitor = \"arc-length\"\n").unwrap();
        assert_eq!(
            plain.moving().unwrap(),
            Some(MovingMesh {
                name: MonitorName::ArcLength,
                monitor: Monitor::ArcLength { scale: 1.0 },
                smoothing: 2.0,
            })
        );
        let curvature = parsed(
            "model = \"sine-gordon-kink\"\n[mesh]\nmonitor = \"curvature\"\n\
             monitor_scale = 3.5\nmonitor_curvature = 0.25\nsmoothing = 0.5\n",
        )
        .unwrap();
        assert_eq!(
            curvature.moving().unwrap(),
            Some(MovingMesh {
                name: MonitorName::Curvature,
                monitor: Monitor::Curvature {
                    scale: 3.5,
                    curvature: 0.25,
                },
                smoothing: 0.5,
            })
        );
        assert_eq!(MonitorName::Curvature.name(), "curvature");
        let fast = FieldScene::load("sine-gordon-kink-fast").unwrap().unwrap();
        assert_eq!(
            fast.moving().unwrap(),
            Some(MovingMesh {
                name: MonitorName::ArcLength,
                monitor: Monitor::ArcLength { scale: 4.0 },
                smoothing: 2.0,
            })
        );
        assert_eq!(fast.mesh.points, Some(101));
        assert_eq!(fast.parameters.get("speed"), Some(&0.99));
    }

    #[test]
    fn moving_mesh_keys_that_would_be_ignored_are_errors_naming_them() {
        let refused = |text: &str, key: &str| match parsed(text) {
            Err(SceneError::NotApplicable { option, .. }) => {
                assert!(option.contains(key), "{option} for {text}");
            }
            other => panic!("{text}: {other:?}"),
        };
        for key in ["monitor_scale", "monitor_curvature", "smoothing"] {
            refused(
                &format!("model = \"phi4-kink\"\n[mesh]\n{key} = 1.0\n"),
                key,
            );
        }
        refused(
            "model = \"phi4-kink\"\n[mesh]\nmonitor = \"arc-length\"\nmonitor_curvature = 1.0\n",
            "monitor_curvature",
        );
        refused(
            "model = \"phi4-kink\"\n[mesh]\nmonitor = \"curvature\"\n\
             [output]\nmultisymplectic_check = false\n",
            "multisymplectic_check",
        );
        assert!(matches!(
            parsed("model = \"phi4-kink\"\n[mesh]\nmonitor = \"uniform\"\n"),
            Err(SceneError::Parse { .. })
        ));
    }

    #[test]
    fn moving_mesh_parameters_on_the_command_line() {
        let with = |pairs: &[(&str, f64)]| Overrides {
            parameters: pairs.iter().map(|(n, v)| (n.to_string(), *v)).collect(),
            ..Overrides::default()
        };
        let mut fast = FieldScene::load("sine-gordon-kink-fast").unwrap().unwrap();
        fast.apply(&with(&[
            ("smoothing", 0.5),
            ("monitor_scale", 9.0),
            ("points", 41.0),
            ("speed", 0.9),
        ]))
        .unwrap();
        assert_eq!(fast.mesh.smoothing, Some(0.5));
        assert_eq!(fast.mesh.monitor_scale, Some(9.0));
        assert_eq!(fast.mesh.points, Some(41));
        assert_eq!(fast.parameters.get("speed"), Some(&0.9));
        assert!(!fast.parameters.contains_key("smoothing"));
        // β only with the curvature monitor; none of them on a uniform mesh.
        assert!(matches!(
            fast.apply(&with(&[("monitor_curvature", 1.0)])),
            Err(SceneError::NotApplicable { option, .. }) if option.contains("monitor_curvature")
        ));
        for key in ["smoothing", "monitor_scale", "monitor_curvature"] {
            let mut uniform = FieldScene::load("sine-gordon-kink").unwrap().unwrap();
            let refused = uniform.apply(&with(&[(key, 1.0)]));
            assert!(
                matches!(&refused, Err(SceneError::NotApplicable { option, .. }) if option.contains(key)),
                "{key}: {refused:?}"
            );
            assert!(refused.unwrap_err().is_bad_input());
        }
    }
}
