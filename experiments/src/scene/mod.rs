//! Scenes: what `svi run` simulates — a model of the zoo and its parameters, an initial
//! state, a method and its options, the step and horizon, and the outputs wanted.
//!
//! A [`Scene`] is a TOML file or a built-in one ([`builtin`]; they reproduce the experiments
//! of Li, Wu, Leok (2018), run each zoo model with its defaults, and stress the methods).
//! Command-line flags ([`Overrides`]) are applied on top of a scene ([`Scene::apply`]), and
//! every option that the scene's model, method or other options cannot use is an error
//! ([`SceneError::NotApplicable`]) rather than silently ignored ([`Scene::check`]). The model
//! decides the space: a zoo model on ℝᴺ (`svi_models::MODEL_NAMES`), a chain or lattice on
//! ℝⁿ with n a parameter (`svi_models::LOCAL_MODEL_NAMES`: `[initial]` vectors of n
//! components, methods svi, svi-newton and verlet), a rigid body on SO(3)
//! (`svi_models::RIGID_MODEL_NAMES`, see [`rigid`] for its `[initial]` and `form`) or a model
//! on another Lie group (`svi_models::GROUP_MODEL_NAMES`, see [`group`]).
//!
//! ```toml
//! model = "kepler"
//!
//! [parameters]          # model parameters, name = value (absent: the model's defaults)
//! e = 0.5
//!
//! [initial]             # optional; absent fields come from the model's default state
//! t0 = 0.0
//! q = [0.5, 0.0]
//! v = [0.0, 1.7320508075688772]   # or p = [...], not both
//!
//! [method]
//! name = "svi"          # NAME, NAME:P or NAME:P/M of svi::method::registry::METHODS:
//!                       # "svi" (default), "svi:7/6", "sc:9", "midpoint", "verlet", ...
//! points = 6            # Chebyshev–Gauss–Lobatto points, svi and sc (default 6): the same
//!                       # as name = "svi:6"
//! quadrature = 12       # Gauss–Legendre points, svi only (default 2 × points)
//!
//! [run]                 # absent: the model's default step and horizon
//! h = 0.2               # the step (unused by adapt = "step", which chooses its own; the
//!                       # step in τ of adapt = "reparam")
//! t_end = 2000.0
//! adapt = "none"        # "none" (default), "step" (step doubling) or "degree" (points per
//!                       # step: methods with points), both to meet `tol`, or "reparam"
//!                       # (fixed steps in τ, dt = g(q) dτ: structure-preserving)
//! # tol = 1e-9          # target final error of adapt = "step" and "degree" (only with them)
//! # monitor = "sundman:1.5"  # g(q) = |q|^1.5 of adapt = "reparam" (only with it; default),
//!                       # or "force:BETA": g = |∂L/∂q(q, 0)|^(−BETA), any model, or
//!                       # "potential": g = 1/L(q, 0) = −1/V(q) (explicit with verlet,
//!                       # yoshida4, kahan-li6 or kahan-li8 on a constant mass)
//! # min_points = 3      # bounds of adapt = "degree" (defaults 3 and 24; only with it)
//! # max_points = 24
//! recovery = "none"     # or "halve-step": retry a failed step as two half steps (adapt =
//!                       # "none" only: the adaptive modes retry failed steps themselves)
//! # max_halvings = 4    # with "halve-step": successive halvings allowed (default 4)
//! # divergence_limit = 1e6   # stop once |q_i| or |p_i| exceeds this (default: no limit)
//! # max_steps = 1000000      # most steps (default and cap 10⁹): an adaptive run that needs
//!                       # more stops with too_many_steps, a fixed grid that does is rejected
//!
//! [output]
//! trajectory = "kepler.csv"   # write the trajectory as CSV (absent: none)
//! # plot = "kepler.svg"       # draw its columns against t as SVG (needs trajectory)
//! every = 10                  # every 10th step (default 1)
//! # output_times = [1.0, 2.5] # report (and write, instead of every step) the states at these
//! #                           # times, read off each step's polynomial (dense output)
//! diagnostics = ["energy", "momentum"]   # the default; add "solution" for the largest error
//!                                        # against the exact solution over the run (its
//!                                        # error at the end is always reported); or ["none"]
//! ```
//!
//! A built-in name wins over a file of the same name (write `./kepler` for the file). Paths in
//! a scene (the trajectory file) are relative to the working directory.
//!
//! Forces (friction, driving) are part of a model's definition: the forced zoo models
//! (`damped-oscillator`, `damped-pendulum`, `driven-oscillator`) are chosen by name like any
//! other, and their force parameters are ordinary `[parameters]`.
//!
//! Instead of `model`, a scene may write its Lagrangian as text (grammar:
//! [`svi::model::text`]; the velocity of coordinate `x` is `vx`), with optional forces and
//! symmetry generators, one expression per coordinate. `[parameters]` then declares every
//! parameter the expressions use, and the scene gives what such a model has no default for:
//! `initial.q`, `initial.v` (or `p`), `run.h` (unless `adapt = "step"`) and `run.t_end`.
//!
//! ```toml
//! lagrangian = "0.5*(vx^2 + vy^2) + mu/sqrt(x^2 + y^2)"
//! coordinates = ["x", "y"]
//! symmetries = [["-y", "x"]]       # optional: generators ξ(q); momenta J1, J2, ...
//! # forces = ["-c*vx", "-c*vy"]    # optional: f_L(t, q, q̇)
//!
//! [parameters]
//! mu = 1.0
//! ```
//!
//! With indexed coordinates (`q[1..n]`, n a parameter) the text is a chain of local terms
//! ([`svi::model::text::chain`]), run like the zoo's chains by every method of ℝᴺ;
//! `boundary` (`"fixed"`, the default, or `"periodic"`) says what an index outside 1..n
//! reads. The `[initial]` vectors of every chain, written as text or not, may be expressions
//! in the site index `i` (from 1) and the parameters, evaluated at every site (a list of
//! them, one per family, for several):
//!
//! ```toml
//! lagrangian = "sum(i, 1, n, 0.5*vq[i]^2) - sum(i, 0, n, 0.5*(q[i+1] - q[i])^2)"
//! coordinates = ["q[1..n]"]
//! boundary = "fixed"
//!
//! [parameters]
//! n = 1000
//!
//! [initial]
//! q = "sin(pi*i/(n+1))"
//! v = "0"
//! ```

pub mod any;
pub mod builtin;
mod check;
pub mod constrained;
pub mod ensemble;
pub mod error;
pub mod events;
pub mod field;
pub mod group;
pub mod limits;
pub mod method;
pub mod overrides;
mod resolve;
pub mod rigid;
pub mod schema;
pub mod spectral;
pub mod vector;

pub use check::CheckedScene;
pub use error::SceneError;

use std::collections::BTreeMap;
use std::path::Path;

use serde::Deserialize;
use svi::MethodSpec;
use svi::lie_group::LieSvi;
use svi::method::registry::{self, SpaceKind};
use svi::model::reparametrized::MonitorSpec;
use svi::model::text::{TextChainModel, TextModel, TextSpec};
use svi_models::{GROUP_MODEL_NAMES, LOCAL_MODEL_NAMES, RIGID_MODEL_NAMES};

use builtin::builtin_scene;
use method::SceneMethod;
use overrides::{Overrides, RunFlags};
use schema::{
    AdaptMode, BoundaryName, Diagnostic, InitialSection, MethodSection, OutputSection,
    RecoveryKind, RunSection,
};

/// A scene: what to simulate and what to report. Absent fields fall back to the model's
/// defaults ([`svi::Defaults`], [`svi::lie_group::RigidBodyDefaults`]) and the method's.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Zoo model name (see [`svi_models::MODEL_NAMES`] and
    /// [`svi_models::RIGID_MODEL_NAMES`]); empty for a Lagrangian written as text.
    #[serde(default)]
    pub model: String,
    /// A Lagrangian written as text, instead of `model` (see [`svi::model::text`] for the
    /// grammar; velocities are `v` + the coordinate's name).
    pub lagrangian: Option<String>,
    /// A Hamiltonian written as text, instead of `model` or `lagrangian` (the same grammar;
    /// momenta are `p` + the coordinate's name). The other text fields are then its own:
    /// `forces` are f_H(t, q, p).
    pub hamiltonian: Option<String>,
    /// The coordinate names of `lagrangian`.
    pub coordinates: Option<Vec<String>>,
    /// The non-conservative force of `lagrangian`, one expression per coordinate.
    pub forces: Option<Vec<String>>,
    /// Symmetry generators ξ(q) of `lagrangian`, each one expression per coordinate.
    pub symmetries: Option<Vec<Vec<String>>>,
    /// What the indexed coordinates of `lagrangian` read outside 1..n (default fixed).
    pub boundary: Option<BoundaryName>,
    /// Holonomic constraints g(q) = 0 of `lagrangian`, one expression each in the coordinates
    /// and the parameters: the scene runs a constrained method ([`constrained`]).
    pub constraints: Option<Vec<String>>,
    /// Model parameters, name → value, applied on top of the model's defaults; for a
    /// Lagrangian written as text, its parameters.
    #[serde(default)]
    pub parameters: BTreeMap<String, f64>,
    /// Initial state; absent fields come from the model's default state.
    #[serde(default)]
    pub initial: InitialSection,
    /// Method and options.
    #[serde(default)]
    pub method: MethodSection,
    /// Step, horizon, adaptivity and failure handling.
    #[serde(default)]
    pub run: RunSection,
    /// Events located during the run (`[[events]]`), see [`events`].
    #[serde(default)]
    pub events: Vec<events::EventSpec>,
    /// Outputs.
    #[serde(default)]
    pub output: OutputSection,
    /// Events given as code by the caller (the Python package's callables), located after
    /// the text `events`. Not a scene field.
    #[serde(skip)]
    pub native_events: Vec<events::NativeEvent>,
    /// The scene file it was read from (none for a built-in scene or a text): no output may
    /// be written over it. Not a scene field.
    #[serde(skip)]
    pub source: Option<std::path::PathBuf>,
}

impl Scene {
    /// Parse a scene from TOML and check it; `origin` names the source in error messages.
    pub fn from_toml(text: &str, origin: &str) -> Result<Scene, SceneError> {
        let scene = Scene::parse(text, origin)?;
        scene.check()?;
        Ok(scene)
    }

    /// Parse a scene from TOML without checking it (a run checks it, once: see
    /// [`Scene::checked`]); `origin` names the source in error messages.
    pub fn parse(text: &str, origin: &str) -> Result<Scene, SceneError> {
        toml::from_str(text).map_err(|parser| SceneError::Parse {
            origin: origin.into(),
            parser,
        })
    }

    /// The scene of a Lagrangian or a Hamiltonian written as text (one of the two given) with
    /// its `coordinates`, `forces`, `symmetries`, `constraints` and `parameters`, every other
    /// field absent (the Python package's `svi.Lagrangian` and `svi.Hamiltonian`): not yet
    /// checked — a text model has no default initial state, step or horizon, which the
    /// caller sets before [`Scene::check`].
    pub fn of_text_model(
        lagrangian: Option<String>,
        hamiltonian: Option<String>,
        coordinates: Vec<String>,
        forces: Option<Vec<String>>,
        symmetries: Option<Vec<Vec<String>>>,
        constraints: Option<Vec<String>>,
        parameters: BTreeMap<String, f64>,
    ) -> Scene {
        let empty: Scene = toml::from_str("").expect("every field of a scene has a default");
        Scene {
            lagrangian,
            hamiltonian,
            coordinates: Some(coordinates),
            forces,
            symmetries,
            constraints,
            parameters,
            ..empty
        }
    }

    /// A built-in scene by name.
    pub fn builtin(name: &str) -> Option<Result<Scene, SceneError>> {
        builtin_scene(name).map(|text| Scene::from_toml(text, &format!("built-in scene '{name}'")))
    }

    /// A built-in scene if `name_or_path` names one, else the scene file at that path (read
    /// only if it is a regular file of at most [`limits::MAX_SCENE_BYTES`]), checked.
    pub fn load(name_or_path: &str) -> Result<Scene, SceneError> {
        let scene = Scene::open(name_or_path)?;
        scene.check()?;
        Ok(scene)
    }

    /// [`Scene::load`] without the check: the scene a run path puts its overrides on
    /// ([`Scene::overlay`]) and then checks once ([`Scene::checked`]).
    pub fn open(name_or_path: &str) -> Result<Scene, SceneError> {
        if let Some(text) = builtin_scene(name_or_path) {
            return Scene::parse(text, &format!("built-in scene '{name_or_path}'"));
        }
        let path = Path::new(name_or_path);
        match limits::read_scene_file(path) {
            Ok(text) => Scene::parse(&text, &format!("'{}'", path.display())).map(|scene| Scene {
                source: Some(path.into()),
                ..scene
            }),
            Err(SceneError::Read { source, .. })
                if source.kind() == std::io::ErrorKind::NotFound
                    && path.extension().is_none()
                    && path.components().count() == 1 =>
            {
                // A built-in space–time scene is one, with the commands that run it (`svi
                // ensemble wave` said "no built-in scene named 'wave'").
                let named =
                    |scenes: &[(&str, &str)]| scenes.iter().any(|(n, _)| *n == name_or_path);
                let (kind, commands) = if named(field::FIELD_SCENES) {
                    (
                        "a field scene (the multisymplectic integrator)",
                        "only `svi run` runs",
                    )
                } else if named(spectral::SPECTRAL_SCENES) {
                    (
                        "a pseudospectral scene",
                        "only `svi run` and `svi bench` run",
                    )
                } else {
                    return Err(SceneError::UnknownScene {
                        name: name_or_path.into(),
                    });
                };
                Err(SceneError::NotApplicable {
                    option: "scene",
                    reason: format!("'{name_or_path}' is {kind}, which {commands}"),
                })
            }
            Err(error) => Err(error),
        }
    }

    /// The name of the scene's model: its zoo name, or [`TextModel::NAME`] for a Lagrangian
    /// written as text.
    pub fn model_name(&self) -> &str {
        if self.is_text() {
            TextModel::NAME
        } else {
            &self.model
        }
    }

    /// Whether the scene writes its model as text (`lagrangian` or `hamiltonian`).
    pub fn is_text(&self) -> bool {
        self.lagrangian.is_some() || self.hamiltonian.is_some()
    }

    /// The scene's Lagrangian or Hamiltonian written as text, as the library reads it (`None`
    /// for a zoo model).
    pub fn text_spec(&self) -> Option<TextSpec> {
        if !self.is_text() {
            return None;
        }
        Some(TextSpec {
            lagrangian: self.lagrangian.clone().unwrap_or_default(),
            hamiltonian: self.hamiltonian.clone().unwrap_or_default(),
            coordinates: self.coordinates.clone().unwrap_or_default(),
            parameters: self
                .parameters
                .iter()
                .map(|(name, value)| (name.clone(), *value))
                .collect(),
            forces: self.forces.clone().unwrap_or_default(),
            symmetries: self.symmetries.clone().unwrap_or_default(),
            boundary: self.boundary.map(Into::into).unwrap_or_default(),
            constraints: self.constraints.clone().unwrap_or_default(),
        })
    }

    /// The scene's Lagrangian written as text, parsed with the scene's parameters: a model
    /// on ℝᴺ, or a chain if its coordinates are indexed (`q[1..n]`); `None` for a zoo model.
    pub fn text(&self) -> Option<Result<Text, SceneError>> {
        let spec = self.text_spec()?;
        Some(
            if spec.is_indexed() {
                TextChainModel::new(&spec).map(Text::Chain)
            } else {
                TextModel::new(&spec).map(Text::Model)
            }
            .map_err(SceneError::from),
        )
    }

    /// Whether the scene's Lagrangian is written as text with indexed coordinates: a chain.
    pub fn is_text_chain(&self) -> bool {
        self.text_spec().is_some_and(|spec| spec.is_indexed())
    }

    /// The space the scene's model lives on: a Lie group for a rigid body on SO(3) or a
    /// model on another group, else ℝᴺ (an unknown model name is reported when the scene
    /// runs).
    pub fn space(&self) -> SpaceKind {
        if self.is_rigid() || GROUP_MODEL_NAMES.contains(&self.model.as_str()) {
            SpaceKind::Group
        } else {
            SpaceKind::Vector
        }
    }

    /// Whether the scene's model is a rigid body on SO(3) (`svi_models::RIGID_MODEL_NAMES`),
    /// with its own `[initial]` fields ([`rigid`]); the other models on groups take those of
    /// [`group`].
    pub fn is_rigid(&self) -> bool {
        RIGID_MODEL_NAMES.contains(&self.model.as_str())
    }

    /// The monitor of `adapt = "reparam"`: `run.monitor` parsed, or the default
    /// (`sundman:1.5`).
    pub fn monitor(&self) -> Result<MonitorSpec, SceneError> {
        match &self.run.monitor {
            Some(text) => Ok(text.parse()?),
            None => Ok(MonitorSpec::default()),
        }
    }

    /// Whether the scene's model is a runtime-dimension one (a chain or lattice of
    /// [`svi_models::LOCAL_MODEL_NAMES`], or a chain written as text, on ℝⁿ with n a
    /// parameter): it runs with every method of ℝᴺ (in O(n) per step with those that keep
    /// its sparsity), and its `[initial]` vectors have n
    /// components or are expressions per site.
    pub fn is_local(&self) -> bool {
        if self.is_text() {
            self.is_text_chain()
        } else {
            LOCAL_MODEL_NAMES.contains(&self.model.as_str())
        }
    }

    /// Apply command-line overrides ([`Scene::overlay`]), then [`Scene::check`].
    pub fn apply(&mut self, overrides: &Overrides) -> Result<(), SceneError> {
        self.overlay(overrides)?;
        self.check()
    }

    /// Put command-line overrides on top, without checking the scene they make (a run checks
    /// it). A flag for a method that does not take it (`--points`, `--quadrature`) or for the
    /// other space (`--form`), and `--h` with `--adapt step`, are errors; a scene's own
    /// `points` and `quadrature` are ignored by a method without them.
    pub fn overlay(&mut self, overrides: &Overrides) -> Result<(), SceneError> {
        let Overrides {
            run:
                RunFlags {
                    method,
                    points,
                    quadrature,
                    h,
                    t_end,
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
            parameters,
            every,
            out,
            plot,
            output_times,
            multipliers,
            event,
            section,
            events_out,
        } = overrides;
        let space = self.space();
        match method {
            Some(SceneMethod::Registry(method)) => {
                method.check_space(space)?;
                // The options written in `--method` replace the scene's; the others carry over.
                self.method.name = Some(SceneMethod::Registry(*method));
                if method.points().is_some() {
                    self.method.points = None;
                }
                if method.quadrature().is_some() {
                    self.method.quadrature = None;
                }
                if space == SpaceKind::Group
                    && method.lie_svi()?.form == svi::lie_group::Form::Reduced
                {
                    self.method.form = None;
                }
            }
            Some(constrained) => self.method.name = Some(constrained.clone()),
            None => {}
        }
        // A constrained scene refuses the registry's method options when it is checked.
        if !self.is_constrained() {
            let name = self.method_name()?;
            for (given, option, takes) in [
                (
                    quadrature.is_some(),
                    "quadrature",
                    name.entry().takes_quadrature(),
                ),
                (points.is_some(), "points", name.entry().takes_points()),
            ] {
                if given && !takes {
                    return Err(SceneError::OptionNotForMethod {
                        option,
                        method: name,
                    });
                }
            }
        }
        if form.is_some() && space == SpaceKind::Vector {
            return Err(SceneError::NotApplicable {
                option: "--form",
                reason: "applies to scenes on Lie groups only (see svi list)".into(),
            });
        }
        set(&mut self.method.points, points);
        set(&mut self.method.quadrature, quadrature);
        set(&mut self.method.form, form);
        set(&mut self.run.h, h);
        set(&mut self.run.t_end, t_end);
        for (name, value) in parameters {
            // A text model's parameters are those its scene declares.
            if self.is_text() && !self.parameters.contains_key(name) {
                let declared: Vec<&str> = self.parameters.keys().map(String::as_str).collect();
                return Err(svi::Error::invalid(
                    name.as_str(),
                    format!(
                        "not a parameter of the text model (parameters: {})",
                        if declared.is_empty() {
                            "none".into()
                        } else {
                            declared.join(", ")
                        }
                    ),
                )
                .into());
            }
            self.parameters.insert(name.clone(), *value);
        }
        set(&mut self.output.every, every);
        set(&mut self.output.trajectory, out);
        set(&mut self.output.plot, plot);
        set(&mut self.output.diagnostics, diagnostics);
        set(&mut self.run.adapt, adapt);
        set(&mut self.run.tol, tol);
        if let Some(monitor) = monitor {
            self.run.monitor = Some(monitor.to_string());
        }
        set(&mut self.output.output_times, output_times);
        set(&mut self.output.multipliers, multipliers);
        self.events.extend(event.iter().cloned());
        set(&mut self.output.section, section);
        set(&mut self.output.events, events_out);
        if *recovery == Some(RecoveryKind::None) {
            self.run.max_halvings = None;
        }
        set(&mut self.run.recovery, recovery);
        set(&mut self.run.divergence_limit, divergence_limit);
        set(&mut self.run.max_steps, max_steps);
        set(&mut self.run.indicators, indicators);
        set(&mut self.run.sensitivity, sensitivity);
        set(&mut self.run.sensitivity_every, sensitivity_every);
        if h.is_some() && self.run.adapt == Some(AdaptMode::Step) {
            return Err(SceneError::NotApplicable {
                option: "--h",
                reason: "not used by --adapt step, which chooses its own steps (the first from \
                         the initial state)"
                    .into(),
            });
        }
        Ok(())
    }

    /// `[method] name`, or the default method of the scene's space (`svi` on ℝᴺ, `lie-svi`
    /// on SO(3)); a constrained method is an error naming the methods the scene takes.
    fn method_name(&self) -> Result<MethodSpec, SceneError> {
        match &self.method.name {
            Some(SceneMethod::Registry(spec)) => Ok(*spec),
            Some(SceneMethod::Constrained(_)) => {
                self.constrained_method()
                    .and(Err(SceneError::NotApplicable {
                        option: "--method (method.name)",
                        reason: "a constrained method runs with svi run or svi.run/svi.solve, not \
                             with this command"
                            .into(),
                    }))
            }
            None => {
                let space = self.space();
                Ok(registry::METHODS
                    .iter()
                    .find(|entry| entry.space == space)
                    .map_or_else(MethodSpec::default, registry::Entry::spec))
            }
        }
    }

    /// The method in use: the method name with `points` and `quadrature` applied on top
    /// (each only for a method that takes it). An error names the method if it is not for
    /// the scene's space, or the option out of range, or if it is a constrained method (see
    /// [`Scene::constrained_method`]).
    pub fn method_spec(&self) -> Result<MethodSpec, SceneError> {
        let mut spec = self.method_name()?;
        spec.check_space(self.space())?;
        if let Some(points) = self.method.points
            && spec.entry().takes_points()
        {
            spec = spec.with_points(points)?;
        }
        if let Some(quadrature) = self.method.quadrature
            && spec.entry().takes_quadrature()
        {
            spec = spec.with_quadrature(quadrature)?;
        }
        Ok(spec)
    }

    /// The Lie-group integrator of a rigid-body scene: [`Scene::method_spec`] in the form of
    /// `[method] form`.
    pub fn lie_svi(&self) -> Result<LieSvi, SceneError> {
        rigid::method(self.method_spec()?, self.method.form)
    }

    /// The number of CGL points in use (`None` for the classic methods or an invalid
    /// method).
    pub fn points(&self) -> Option<usize> {
        self.method_spec().ok()?.points_in_use()
    }

    /// The number of Gauss–Legendre points in use (`None` for the methods without or an
    /// invalid method).
    pub fn quadrature(&self) -> Option<usize> {
        self.method_spec().ok()?.quadrature_in_use()
    }

    /// Whether `diagnostic` is asked for (by default [`Scene::DEFAULT_DIAGNOSTICS`]).
    pub fn wants(&self, diagnostic: Diagnostic) -> bool {
        match &self.output.diagnostics {
            Some(wanted) => wanted.contains(&diagnostic),
            None => Self::DEFAULT_DIAGNOSTICS.contains(&diagnostic),
        }
    }

    /// The diagnostics of a scene that names none: energy and momenta, which cost an
    /// evaluation of L and a dot product per step. The error against the exact solution
    /// (Kepler: solving Kepler's equation, as much again as the step) is measured at every
    /// step only when asked for; its value at the end is always reported.
    pub const DEFAULT_DIAGNOSTICS: [Diagnostic; 2] = [Diagnostic::Energy, Diagnostic::Momentum];

    /// Whether `diagnostic` is listed in the scene's (or `--diagnostics`') list.
    fn wants_explicitly(&self, diagnostic: Diagnostic) -> bool {
        self.output
            .diagnostics
            .as_ref()
            .is_some_and(|wanted| wanted.contains(&diagnostic))
    }

    /// Whether any diagnostic is asked for: not `none` and not an empty list. Rigid-body runs
    /// measure their invariants and ‖RᵀR − I‖ whenever this holds.
    pub fn measures(&self) -> bool {
        self.output.diagnostics.as_ref().is_none_or(|wanted| {
            wanted
                .iter()
                .any(|diagnostic| *diagnostic != Diagnostic::None)
        })
    }
}

impl Scene {
    /// A diagnostic asked for by name that the scene's model cannot give: an error naming
    /// the option (it would otherwise be a silent `null`).
    fn not_measurable(&self, option: &'static str, what: &str) -> SceneError {
        SceneError::NotApplicable {
            option,
            reason: format!("the model '{}' {what}", self.model_name()),
        }
    }
}

/// A Lagrangian written as text, parsed: a model on ℝᴺ or a chain of indexed coordinates.
#[derive(Debug, Clone, PartialEq)]
pub enum Text {
    /// Named coordinates: a [`svi::model::text::TextLagrangian`] of run-time size.
    Model(TextModel),
    /// Indexed coordinates and sums: a [`svi::model::text::TextChain`] of local terms.
    Chain(TextChainModel),
}

/// `target = value` if a value is given.
pub(crate) fn set<T: Clone>(target: &mut Option<T>, value: &Option<T>) {
    if let Some(value) = value {
        *target = Some(value.clone());
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::*;
    use svi::{Recovery, RunOptions};
    use svi_models::{MODEL_NAMES, RIGID_MODEL_NAMES};

    /// A built-in scene (tests of other modules use it too).
    pub(crate) fn scene(name: &str) -> Scene {
        Scene::builtin(name).expect("built-in").expect("parses")
    }

    /// A method written `name`, `name:P` or `name:P/M`.
    pub(crate) fn method(text: &str) -> MethodSpec {
        text.parse().expect("a method")
    }

    #[test]
    fn every_builtin_scene_parses_and_names_a_zoo_model() {
        assert_eq!(
            builtin_scene_names(),
            [
                "oscillator",
                "kepler",
                "kepler-text",
                "kepler-h-text",
                "pendulum",
                "spring-pendulum",
                "double-pendulum",
                "damped-oscillator",
                "damped-pendulum",
                "driven-oscillator",
                "stiff-spring-pendulum",
                "stiff-spring-pendulum-coarse",
                "stiff-spring-pendulum-multiscale",
                "kepler-long",
                "kepler-e0.9",
                "kepler-e0.99",
                "kepler-recovery",
                "double-pendulum-chaotic",
                "henon-heiles",
                "restricted-three-body",
                "kepler-h",
                "pendulum-h",
                "henon-heiles-h",
                "magnetic-bottle",
                "oscillator-beyond-stability",
                "outer-solar-system",
                "spherical-pendulum",
                "double-pendulum-cartesian",
                "four-bar-linkage",
                "fput",
                "fput-text",
                "fput-stiff",
                "toda",
                "relativistic-chain",
                "sine-gordon-chain",
                "rigid-body",
                "heavy-top",
                "pendulum-3d",
                "falling-body",
                "dual-spin",
                "spherical-chain"
            ]
        );
        for name in builtin_scene_names() {
            let scene = scene(name);
            let model = scene.model_name();
            assert!(
                MODEL_NAMES.contains(&model)
                    || RIGID_MODEL_NAMES.contains(&model)
                    || GROUP_MODEL_NAMES.contains(&model)
                    || LOCAL_MODEL_NAMES.contains(&model)
                    || scene.is_text(),
                "{name}"
            );
            assert_eq!(
                scene.is_local(),
                LOCAL_MODEL_NAMES.contains(&model) || scene.is_text_chain(),
                "{name}"
            );
            if MODEL_NAMES.contains(&name) || LOCAL_MODEL_NAMES.contains(&name) {
                assert_eq!(scene.model, name);
                assert_eq!(scene.method.name, Some(method("svi").into()));
            } else if scene.constraints.is_some() {
                // Named after the mechanism its Lagrangian and constraints describe.
                assert_eq!(scene.model_name(), "text", "{name}");
            } else if name == "outer-solar-system" {
                // Named after the bodies HLW integrate.
                assert_eq!(scene.model, "nbody");
            } else {
                // The stress scenes are named after their model.
                assert!(name.contains(scene.model_name()), "{name}");
            }
        }
        assert!(Scene::builtin("kepler2").is_none());
    }

    #[test]
    fn oscillator_scene_is_the_papers_setting() {
        let scene = scene("oscillator");
        assert_eq!(scene.parameters["sigma"], 1.0);
        assert_eq!(scene.initial.t0, Some(0.0));
        assert_eq!(scene.initial.q, Some(schema::Components::Values(vec![0.0])));
        assert_eq!(scene.initial.p, Some(schema::Components::Values(vec![1.0])));
        assert_eq!(scene.initial.v, None);
        assert_eq!(scene.run.h, Some(1.0));
        assert_eq!(scene.run.t_end, Some(100.0));
        assert_eq!(scene.points(), Some(9));
        assert_eq!(scene.quadrature(), Some(18));
        assert!(scene.output.trajectory.is_none());
        assert!(scene.wants(Diagnostic::Energy) && scene.wants(Diagnostic::Momentum));
        assert!(!scene.wants(Diagnostic::Solution) && !scene.wants(Diagnostic::None));
    }

    #[test]
    fn kepler_scene_is_the_papers_setting() {
        let scene = scene("kepler");
        assert_eq!(scene.parameters["e"], 0.5);
        assert_eq!(scene.initial, InitialSection::default());
        assert_eq!(scene.run.h, Some(0.2));
        assert_eq!(scene.run.t_end, Some(2000.0));
        assert_eq!(scene.points(), Some(6));
        assert_eq!(scene.quadrature(), Some(12));
        assert_eq!(DEFAULT_SCENE, "kepler");
    }

    #[test]
    fn the_other_scenes_use_the_model_defaults() {
        for name in ["pendulum", "spring-pendulum", "double-pendulum"] {
            let scene = scene(name);
            assert!(scene.parameters.is_empty(), "{name}");
            assert_eq!(scene.initial, InitialSection::default(), "{name}");
            assert_eq!(scene.run, RunSection::default(), "{name}");
            assert_eq!(scene.points(), Some(6), "{name}");
        }
    }

    #[test]
    fn a_minimal_scene_falls_back_to_defaults() {
        let scene = Scene::from_toml("model = \"pendulum\"\n", "test").unwrap();
        assert_eq!(scene.method_spec().unwrap(), method("svi"));
        assert_eq!(scene.points(), Some(svi::Svi::default().points));
        assert_eq!(scene.quadrature(), Some(2 * svi::Svi::default().points));
        assert_eq!(scene.output, OutputSection::default());
    }

    #[test]
    fn overrides_replace_scene_fields() {
        let mut scene = scene("kepler");
        scene
            .apply(&Overrides {
                run: RunFlags {
                    method: Some(method("svi").into()),
                    points: Some(5),
                    quadrature: Some(7),
                    h: Some(0.05),
                    t_end: Some(10.0),
                    diagnostics: Some(vec![Diagnostic::Energy]),
                    adapt: Some(AdaptMode::Degree),
                    tol: Some(1e-9),
                    monitor: None,
                    recovery: None,
                    divergence_limit: None,
                    max_steps: Some(500),
                    form: None,
                    indicators: None,
                    sensitivity: None,
                    sensitivity_every: None,
                },
                parameters: vec![("e".into(), 0.9)],
                every: Some(10),
                out: Some("x.csv".into()),
                plot: Some("x.svg".into()),
                output_times: None,
                multipliers: None,
                event: vec!["peri: q1*vq1 + q2*vq2 @up".parse().unwrap()],
                section: None,
                events_out: Some("events.csv".into()),
            })
            .unwrap();
        assert_eq!(scene.events.len(), 1);
        assert_eq!(scene.output.events, Some("events.csv".into()));
        assert_eq!(scene.run.max_steps, Some(500));
        assert_eq!(scene.run.adapt, Some(AdaptMode::Degree));
        assert_eq!(scene.run.tol, Some(1e-9));
        // Output times replace the thinned steps of the trajectory: not with --every.
        let times = Overrides {
            output_times: Some(vec![1.0, 2.0]),
            ..Overrides::default()
        };
        let error = scene.clone().apply(&times).unwrap_err();
        assert!(
            matches!(error, SceneError::NotApplicable { option, .. } if option.starts_with("--every")),
            "{error}"
        );
        let mut dense = self::scene("kepler");
        dense.apply(&times).unwrap();
        assert_eq!(dense.output.output_times, Some(vec![1.0, 2.0]));
        // Recovery is for fixed-step runs only.
        let recovery = Overrides {
            run: RunFlags {
                recovery: Some(RecoveryKind::HalveStep),
                divergence_limit: Some(1e9),
                ..RunFlags::default()
            },
            ..Overrides::default()
        };
        assert!(scene.clone().apply(&recovery).is_err());
        let mut fixed = self::scene("kepler");
        fixed.apply(&recovery).unwrap();
        assert_eq!(fixed.run.recovery, Some(RecoveryKind::HalveStep));
        assert_eq!(
            fixed.run.options().unwrap(),
            RunOptions::default()
                .with_recovery(Recovery::HalveStep {
                    max_halvings: DEFAULT_MAX_HALVINGS
                })
                .with_divergence_limit(1e9)
        );
        assert_eq!(scene.points(), Some(5));
        assert_eq!(scene.quadrature(), Some(7));
        assert_eq!(scene.run.h, Some(0.05));
        assert_eq!(scene.run.t_end, Some(10.0));
        assert_eq!(scene.parameters["e"], 0.9);
        assert_eq!(scene.output.every, Some(10));
        assert_eq!(scene.output.trajectory, Some("x.csv".into()));
        assert_eq!(scene.output.plot, Some("x.svg".into()));
        assert!(scene.wants(Diagnostic::Energy));
        assert!(!scene.wants(Diagnostic::Momentum));
        assert!(!scene.wants(Diagnostic::Solution));
    }

    #[test]
    fn points_without_quadrature_keep_the_papers_rule() {
        let mut scene = scene("oscillator");
        scene
            .apply(&Overrides {
                run: RunFlags {
                    points: Some(4),
                    ..RunFlags::default()
                },
                ..Overrides::default()
            })
            .unwrap();
        assert_eq!(scene.quadrature(), Some(8));
    }

    #[test]
    fn switching_to_sc_drops_the_quadrature_and_rejects_it_as_a_flag() {
        let mut scene = scene("kepler");
        scene
            .apply(&Overrides {
                run: RunFlags {
                    method: Some(method("sc").into()),
                    ..RunFlags::default()
                },
                ..Overrides::default()
            })
            .unwrap();
        assert_eq!(scene.quadrature(), None);
        let error = scene
            .apply(&Overrides {
                run: RunFlags {
                    quadrature: Some(12),
                    ..RunFlags::default()
                },
                ..Overrides::default()
            })
            .unwrap_err();
        assert!(matches!(
            error,
            SceneError::OptionNotForMethod {
                option: "quadrature",
                method
            } if method == self::method("sc")
        ));
    }

    #[test]
    fn scene_format_errors_name_the_line() {
        let text = "model = \"kepler\"\n[run]\nh = 0.1\nstep = 3\n";
        let error = Scene::from_toml(text, "'test.toml'").unwrap_err();
        let SceneError::Parse { origin, parser } = &error else {
            panic!("{error}")
        };
        assert_eq!(origin, "'test.toml'");
        let message = parser.to_string();
        assert!(message.contains("line 4"), "{message}");
        assert!(message.contains("step"), "{message}");
    }

    #[test]
    fn a_parse_error_writes_long_numbers_short() {
        // The TOML parser writes the float 1e-300 with its 300 digits; the message does not.
        let text = "model = \"kepler\"\n[method]\nname = 1e-300\n";
        let message = Scene::from_toml(text, "'t.toml'").unwrap_err().to_string();
        assert!(
            message.starts_with("cannot parse scene 't.toml': "),
            "{message}"
        );
        assert!(message.contains("line 3"), "{message}");
        assert!(message.contains("floating point `1e-300`"), "{message}");
        assert!(message.len() < 300, "{message}");
        // Numbers of fewer than 17 digits stay as written.
        let text = "model = \"kepler\"\n[run]\nh = \"1e-22\"\n";
        let message = Scene::from_toml(text, "t").unwrap_err().to_string();
        assert!(message.contains("string \"1e-22\""), "{message}");
    }

    #[test]
    fn unknown_method_and_diagnostic_names_are_listed() {
        let error =
            Scene::from_toml("model = \"kepler\"\n[method]\nname = \"rk45\"\n", "t").unwrap_err();
        let SceneError::Parse { parser, .. } = &error else {
            panic!("{error}")
        };
        assert!(parser.to_string().contains(
            "unknown method 'rk45' (known: svi, svi-newton, svi-h, sc, sc-h, symplectic-euler,"
        ));
        let text = "model = \"kepler\"\n[output]\ndiagnostics = [\"energy\", \"angular\"]\n";
        let SceneError::Parse { parser, .. } = Scene::from_toml(text, "t").unwrap_err() else {
            panic!()
        };
        let message = parser.to_string();
        assert!(
            message.contains("unknown diagnostic 'angular'"),
            "{message}"
        );
        assert!(message.contains("line 3"), "{message}");
    }

    #[test]
    fn a_missing_bare_name_is_an_unknown_scene_and_a_missing_path_a_read_error() {
        let error = Scene::load("keppler").unwrap_err();
        assert!(matches!(error, SceneError::UnknownScene { .. }));
        assert!(error.to_string().contains("oscillator, kepler"), "{error}");
        // A field or pseudospectral scene is named as one: `Scene` holds neither.
        for (name, kind) in [
            ("wave", "a field scene"),
            ("nls-soliton", "a pseudospectral"),
        ] {
            let error = Scene::load(name).unwrap_err().to_string();
            assert!(
                error.starts_with(&format!("scene: '{name}' is {kind}")),
                "{error}"
            );
        }
        let path = std::env::temp_dir().join("svi-cli-no-such-dir/scene.toml");
        let error = Scene::load(path.to_str().unwrap()).unwrap_err();
        assert!(matches!(error, SceneError::Read { .. }), "{error}");
    }

    #[test]
    fn none_means_no_diagnostic() {
        let mut scene = scene("oscillator");
        assert!(scene.measures() && scene.wants(Diagnostic::Energy));
        assert!(!scene.wants(Diagnostic::None));
        for list in [vec![Diagnostic::None], vec![]] {
            scene.output.diagnostics = Some(list);
            assert!(!scene.measures());
            assert!(!scene.wants(Diagnostic::Energy));
        }
        scene.output.diagnostics = Some(vec![Diagnostic::Momentum]);
        assert!(scene.measures() && !scene.wants(Diagnostic::Energy));
    }
}
