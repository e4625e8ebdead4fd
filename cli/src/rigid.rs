//! Rigid-body scenes on SO(3): the free rigid body, the heavy top and the 3D pendulum,
//! integrated by the Lie-group variational integrator [`LieSvi`].
//!
//! A rigid-body scene is a TOML file like the others, with a rigid-body model
//! ([`svi_models::RIGID_MODEL_NAMES`]) and an attitude instead of a configuration vector:
//!
//! ```toml
//! model = "heavy-top"
//!
//! [parameters]          # absent: the model's defaults
//! m = 1.0
//!
//! [initial]             # optional
//! rotation = [0.5, 0.0, 0.0]   # R0 = exp(rotation^), or quaternion = [w, x, y, z]
//! omega = [0.0, 0.0, 10.0]     # body angular velocity, or momentum = [...] (body)
//!
//! [method]
//! name = "lie-svi"      # or "lie-svi-reduced", with options: "lie-svi:3/3", "lie-svi-reduced:4"
//! points = 3            # Chebyshev–Gauss–Lobatto points (default 3), on top of name
//! quadrature = 3        # Gauss–Legendre points (default = points), on top of name
//! form = "full"         # or "reduced" (discrete Euler–Poincaré; G-invariant models only);
//!                       # name = "lie-svi-reduced" is form = "reduced"
//!
//! [run]
//! h = 0.01
//! t_end = 20.0
//!
//! [output]
//! trajectory = "top.csv"      # t, quaternion, rotation matrix, Ω, Π, energy, ‖RᵀR − I‖
//! every = 10
//! diagnostics = ["energy", "momentum"]
//! ```
//!
//! The command line reaches this module through two hooks: `svi run` asks
//! [`RigidScene::load_if_rigid`] first (a built-in rigid scene, or a scene file whose model
//! is a rigid-body model), and `svi list` prints [`list_lines`]. The summary adds
//! `orthogonality_error_max` (‖RᵀR − I‖_F over the step points) and reports the
//! conservation of the spatial angular momenta about the model's symmetry axes as
//! `momentum_error_max`.

use std::collections::BTreeMap;
use std::fmt;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;

use nalgebra::{SMatrix, SVector};
use serde::{Deserialize, Serialize};
use svi::MethodSpec;
use svi::lie_group::so3::{exp, orthogonality_error};
use svi::lie_group::{
    AngularMomentumError, Form, LieSvi, OrthogonalityError, RigidBodyExt, RigidBodyIntegrator,
    RigidInitial, RigidPoint, RigidTrajectory,
};
use svi::method::registry::SpaceKind;
use svi::observer::{EnergyError, Every, InvariantError};
use svi_models::{RIGID_MODEL_NAMES, RigidModelVisitor, RigidZooModel, visit_rigid_model};

use crate::{Diagnostic, Float, Overrides, Parameters, Progress, SceneError, TrajectoryOutput};

/// The built-in rigid-body scenes, as (name, TOML text).
pub const RIGID_SCENES: &[(&str, &str)] = &[
    ("rigid-body", include_str!("../scenes/rigid-body.toml")),
    ("heavy-top", include_str!("../scenes/heavy-top.toml")),
    ("pendulum-3d", include_str!("../scenes/pendulum-3d.toml")),
];

/// The name of the rigid-body method in summaries (whichever form; the summary's `form`
/// says which).
pub const METHOD_NAME: &str = "lie-svi";

/// The TOML text of a built-in rigid-body scene.
pub fn rigid_scene(name: &str) -> Option<&'static str> {
    RIGID_SCENES
        .iter()
        .find(|(scene, _)| *scene == name)
        .map(|(_, text)| *text)
}

/// A rigid-body scene. Absent fields fall back to the model's
/// [`svi::lie_group::RigidBodyDefaults`] and the method's defaults.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RigidScene {
    /// Rigid-body model name (see [`RIGID_MODEL_NAMES`]).
    pub model: String,
    /// Model parameters, name → value.
    #[serde(default)]
    pub parameters: BTreeMap<String, f64>,
    /// Initial attitude and angular velocity or momentum.
    #[serde(default)]
    pub initial: RigidInitialSection,
    /// Method options.
    #[serde(default)]
    pub method: RigidMethodSection,
    /// Step and horizon.
    #[serde(default)]
    pub run: crate::RunSection,
    /// Outputs.
    #[serde(default)]
    pub output: crate::OutputSection,
}

/// `[initial]` of a rigid-body scene.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RigidInitialSection {
    /// Initial time.
    pub t0: Option<f64>,
    /// R₀ as a rotation vector (R₀ = exp(rotation^)); excludes `quaternion`.
    pub rotation: Option<Vec<f64>>,
    /// R₀ as a unit quaternion (w, x, y, z); excludes `rotation`.
    pub quaternion: Option<Vec<f64>>,
    /// Body angular velocity Ω₀; excludes `momentum`.
    pub omega: Option<Vec<f64>>,
    /// Body angular momentum Π₀; excludes `omega`.
    pub momentum: Option<Vec<f64>>,
}

/// `[method]` of a rigid-body scene.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RigidMethodSection {
    /// `lie-svi` (the default) or `lie-svi-reduced`, written `name`, `name:P` or
    /// `name:P/M`.
    #[serde(
        default,
        deserialize_with = "crate::scene::schema::optional_method_spec"
    )]
    pub name: Option<MethodSpec>,
    /// Chebyshev–Gauss–Lobatto points, on top of `name` (default 3).
    pub points: Option<usize>,
    /// Gauss–Legendre points, on top of `name` (default: `points`).
    pub quadrature: Option<usize>,
    /// `full` (default) or `reduced`; `lie-svi-reduced` means `reduced`.
    pub form: Option<String>,
}

/// Parse a form name.
pub fn parse_form(name: &str) -> Result<Form, SceneError> {
    match name {
        "full" => Ok(Form::Full),
        "reduced" => Ok(Form::Reduced),
        _ => Err(svi::Error::invalid(
            "form",
            format!("unknown form '{name}' (known: full, reduced)"),
        )
        .into()),
    }
}

/// Name of a form.
fn form_name(form: Form) -> &'static str {
    match form {
        Form::Full => "full",
        Form::Reduced => "reduced",
    }
}

/// Read a fixed-length vector from a scene field.
fn fixed<const K: usize>(field: &str, values: &[f64]) -> Result<SVector<f64, K>, SceneError> {
    if values.len() != K {
        return Err(svi::Error::invalid(
            format!("initial.{field}"),
            format!("{} components; need {K}", values.len()),
        )
        .into());
    }
    Ok(SVector::from_iterator(values.iter().copied()))
}

/// The rotation matrix of a unit quaternion (w, x, y, z).
fn rotation_from_quaternion(q: &SVector<f64, 4>) -> Result<SMatrix<f64, 3, 3>, SceneError> {
    let norm = q.norm();
    if !norm.is_finite() || (norm - 1.0).abs() > 1e-10 {
        return Err(svi::Error::invalid(
            "initial.quaternion",
            format!("norm {norm}; a unit quaternion is needed"),
        )
        .into());
    }
    Ok(svi::lie_group::rotation(&[q[0], q[1], q[2], q[3]]))
}

impl RigidScene {
    /// Parse a rigid-body scene from TOML; `origin` names the source in error messages.
    pub fn from_toml(text: &str, origin: &str) -> Result<RigidScene, SceneError> {
        let scene: RigidScene = toml::from_str(text).map_err(|source| SceneError::Parse {
            origin: origin.into(),
            source,
        })?;
        scene.check()?;
        Ok(scene)
    }

    /// A rigid-body scene if `name_or_path` is a built-in rigid-body scene or a readable
    /// TOML file whose `model` is a rigid-body model; `None` otherwise (the caller then
    /// treats it as an ordinary scene).
    pub fn load_if_rigid(name_or_path: &str) -> Option<Result<RigidScene, SceneError>> {
        if let Some(text) = rigid_scene(name_or_path) {
            return Some(RigidScene::from_toml(
                text,
                &format!("built-in scene '{name_or_path}'"),
            ));
        }
        let path = Path::new(name_or_path);
        let text = std::fs::read_to_string(path).ok()?;
        let table: toml::Table = toml::from_str(&text).ok()?;
        let model = table.get("model")?.as_str()?;
        RIGID_MODEL_NAMES
            .contains(&model)
            .then(|| RigidScene::from_toml(&text, &format!("'{}'", path.display())))
    }

    /// Consistency checks that need no model.
    pub fn check(&self) -> Result<(), SceneError> {
        let initial = &self.initial;
        if initial.rotation.is_some() && initial.quaternion.is_some() {
            return Err(svi::Error::invalid(
                "initial",
                "both rotation and quaternion are given: give one of them",
            )
            .into());
        }
        if initial.omega.is_some() && initial.momentum.is_some() {
            return Err(svi::Error::invalid(
                "initial",
                "both omega and momentum are given: give one of them",
            )
            .into());
        }
        self.method()?;
        match (self.output.every, &self.output.trajectory) {
            (Some(_), None) => Err(SceneError::EveryWithoutOutput),
            (Some(0), Some(_)) => {
                Err(svi::Error::invalid("every", "0 steps; need at least 1").into())
            }
            _ => Ok(()),
        }
    }

    /// Apply command-line overrides (`--method` takes the rigid-body methods only) and an
    /// optional `--form`.
    pub fn apply(&mut self, overrides: &Overrides, form: Option<&str>) -> Result<(), SceneError> {
        if let Some(method) = overrides.method {
            // The options and the form written in `--method` replace the scene's.
            let built = method.lie_svi()?;
            self.method.name = Some(method);
            if method.points().is_some() {
                self.method.points = None;
            }
            if method.quadrature().is_some() {
                self.method.quadrature = None;
            }
            if built.form == Form::Reduced {
                self.method.form = None;
            }
        }
        let Overrides {
            points,
            quadrature,
            h,
            t_end,
            parameters,
            every,
            out,
            diagnostics,
            ..
        } = overrides;
        crate::scene::set(&mut self.method.points, points);
        crate::scene::set(&mut self.method.quadrature, quadrature);
        if let Some(form) = form {
            self.method.form = Some(form.into());
        }
        crate::scene::set(&mut self.run.h, h);
        crate::scene::set(&mut self.run.t_end, t_end);
        for (name, value) in parameters {
            self.parameters.insert(name.clone(), *value);
        }
        crate::scene::set(&mut self.output.every, every);
        crate::scene::set(&mut self.output.trajectory, out);
        crate::scene::set(&mut self.output.diagnostics, diagnostics);
        self.check()
    }

    /// Whether `diagnostic` is asked for.
    pub fn wants(&self, diagnostic: Diagnostic) -> bool {
        self.output
            .diagnostics
            .as_ref()
            .is_none_or(|wanted| wanted.contains(&diagnostic))
    }

    /// The method the scene asks for: `[method] name` (default `lie-svi`) with `points`,
    /// `quadrature` and `form` applied on top. An error names a method that is not for rigid
    /// bodies, an option out of range, or a form that contradicts `lie-svi-reduced`.
    pub fn method(&self) -> Result<LieSvi, SceneError> {
        let mut spec = match self.method.name {
            Some(spec) => spec,
            None => METHOD_NAME.parse()?,
        };
        spec.check_space(SpaceKind::Rotation)?;
        if let Some(points) = self.method.points {
            spec = spec.with_points(points)?;
        }
        if let Some(quadrature) = self.method.quadrature {
            spec = spec.with_quadrature(quadrature)?;
        }
        let mut method = spec.lie_svi()?;
        if let Some(form) = &self.method.form {
            let form = parse_form(form)?;
            if method.form == Form::Reduced && form == Form::Full {
                return Err(svi::Error::invalid(
                    "form",
                    format!(
                        "form \"full\" contradicts method '{spec}' (use lie-svi for the full form)"
                    ),
                )
                .into());
            }
            method = method.with_form(form);
        }
        Ok(method)
    }

    /// Integrate the scene, write its trajectory if asked, and summarise; `progress` shows a
    /// bar on stderr for runs of at least [`crate::PROGRESS_MIN_STEPS`] steps.
    pub fn run(&self, progress: bool) -> Result<RigidSummary, SceneError> {
        self.check()?;
        visit_rigid_model(
            &self.model,
            RunRigid {
                scene: self,
                progress,
            },
        )
        .unwrap_or_else(|| {
            Err(svi::Error::invalid(
                "model",
                format!(
                    "unknown rigid-body model '{}' (known: {})",
                    self.model,
                    RIGID_MODEL_NAMES.join(", ")
                ),
            )
            .into())
        })
    }
}

/// Receives the model of a rigid-body scene and runs it.
struct RunRigid<'a> {
    scene: &'a RigidScene,
    progress: bool,
}

impl RigidModelVisitor for RunRigid<'_> {
    type Output = Result<RigidSummary, SceneError>;

    fn visit<M: RigidZooModel>(self, mut model: M) -> Self::Output {
        let scene = self.scene;
        for (name, value) in &scene.parameters {
            model.set_parameter(name, *value)?;
        }
        let (default_r, default_omega) = model.initial_state();
        let r = match (&scene.initial.rotation, &scene.initial.quaternion) {
            (Some(rotation), _) => exp(&fixed::<3>("rotation", rotation)?),
            (None, Some(q)) => rotation_from_quaternion(&fixed::<4>("quaternion", q)?)?,
            (None, None) => default_r,
        };
        let initial = match (&scene.initial.omega, &scene.initial.momentum) {
            (Some(omega), _) => RigidInitial::Velocity {
                r,
                omega: fixed::<3>("omega", omega)?,
            },
            (None, Some(momentum)) => RigidInitial::Momentum {
                r,
                momentum: fixed::<3>("momentum", momentum)?,
            },
            (None, None) => RigidInitial::Velocity {
                r,
                omega: default_omega,
            },
        };
        let t0 = scene.initial.t0.unwrap_or(0.0);
        let h = scene.run.h.unwrap_or_else(|| model.default_step());
        let t_end = scene
            .run
            .t_end
            .unwrap_or_else(|| t0 + model.default_horizon());
        let method = scene.method()?;
        let integrator = RigidBodyIntegrator::new(model, method.clone());
        let model = integrator.model();
        let every = scene.output.every.unwrap_or(1);
        let mut observers = (
            scene.wants(Diagnostic::Energy).then(EnergyError::default),
            (scene.wants(Diagnostic::Momentum) && model.axis_count() > 0)
                .then(AngularMomentumError::default),
            (model.invariant_count() > 0).then(InvariantError::default),
            OrthogonalityError::default(),
            scene
                .output
                .trajectory
                .as_ref()
                .map(|_| Every::new(every, RigidTrajectory::new())),
            self.progress
                .then(|| Progress::for_run(t0, h, t_end))
                .flatten(),
        );
        let start = Instant::now();
        let run = integrator.run(t0, initial, h, t_end, &mut observers);
        let seconds = start.elapsed().as_secs_f64();
        if let Some(progress) = &observers.5 {
            progress.finish();
        }
        let run = run?;
        let (energy, momentum, invariants, orthogonality, trajectory, _) = observers;
        let first = integrator.initial_state(t0, &initial)?;
        let first = integrator.phase_point(t0, &first, &SVector::zeros())?;
        let last = run.last;

        let trajectory = match (trajectory, &scene.output.trajectory) {
            (Some(Every { every, inner }), Some(path)) => {
                let mut rows = inner.points;
                if !run.statistics.steps.is_multiple_of(every.max(1)) {
                    rows.push(last);
                }
                write_trajectory(path, model, &rows)?;
                Some(TrajectoryOutput {
                    path: path.display().to_string(),
                    every,
                    rows: rows.len(),
                })
            }
            _ => None,
        };
        let info = method.info();
        let spatial = last.spatial_momentum();
        Ok(RigidSummary {
            model: model.name().into(),
            parameters: Parameters(model.parameters()),
            method: METHOD_NAME.into(),
            form: form_name(method.form).into(),
            points: method.points,
            quadrature: method.quadrature_points(),
            order: info.order,
            symmetric: info.symmetric,
            symplectic: info.symplectic,
            h,
            t0,
            t_end: last.t,
            steps: run.statistics.steps,
            attitude: last.r.transpose().iter().copied().collect(),
            quaternion: last.quaternion().to_vec(),
            omega: last.omega.iter().copied().collect(),
            momentum: last.momentum.iter().copied().collect(),
            spatial_momentum: spatial.iter().copied().collect(),
            energy_initial: model.energy(&first.r, &first.omega),
            energy_final: model.energy(&last.r, &last.omega),
            energy_error_max: energy.map(|e| e.max),
            momentum_names: (0..model.axis_count())
                .map(|i| model.axis_name(i))
                .collect(),
            momentum_error_max: momentum.as_ref().map(|m| m.max),
            momentum_error_relative: momentum.as_ref().map(AngularMomentumError::relative),
            invariant_names: (0..model.invariant_count())
                .map(|i| model.invariant_name(i))
                .collect(),
            invariant_error_max: invariants.map(|i| i.max),
            orthogonality_error_max: orthogonality.max,
            orthogonality_error_final: orthogonality_error(&last.r),
            iterations: run.statistics.iterations,
            evaluations: run.statistics.evaluations,
            seconds,
            trajectory,
        })
    }
}

/// The CSV header of a rigid-body trajectory (with its newline).
pub const RIGID_CSV_HEADER: &str = "t,qw,qx,qy,qz,r11,r12,r13,r21,r22,r23,r31,r32,r33,\
omega_1,omega_2,omega_3,pi_1,pi_2,pi_3,energy,orthogonality\n";

/// Write `rows` as CSV (see [`RIGID_CSV_HEADER`]), full precision.
fn write_trajectory<M: RigidZooModel>(
    path: &Path,
    model: &M,
    rows: &[RigidPoint],
) -> Result<(), SceneError> {
    let write = || -> std::io::Result<()> {
        let mut out = BufWriter::new(File::create(path)?);
        out.write_all(RIGID_CSV_HEADER.as_bytes())?;
        for point in rows {
            write!(out, "{}", Float(point.t))?;
            let quaternion = point.quaternion();
            let matrix = point.r.transpose();
            for x in quaternion
                .iter()
                .chain(matrix.iter())
                .chain(point.omega.iter())
                .chain(point.momentum.iter())
            {
                write!(out, ",{}", Float(*x))?;
            }
            let energy = model.energy(&point.r, &point.omega);
            writeln!(
                out,
                ",{},{}",
                Float(energy),
                Float(orthogonality_error(&point.r))
            )?;
        }
        out.flush()
    };
    write().map_err(|source| SceneError::Write {
        path: PathBuf::from(path),
        source,
    })
}

/// The result of running a rigid-body scene (`svi run --json` prints it as one object).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RigidSummary {
    /// Model name.
    pub model: String,
    /// Model parameters in effect.
    pub parameters: Parameters,
    /// `lie-svi`.
    pub method: String,
    /// `full` or `reduced`.
    pub form: String,
    /// Chebyshev–Gauss–Lobatto points.
    pub points: usize,
    /// Gauss–Legendre points.
    pub quadrature: usize,
    /// Classical order.
    pub order: usize,
    /// Whether the method is symmetric.
    pub symmetric: bool,
    /// Whether the method is symplectic.
    pub symplectic: bool,
    /// Step size.
    pub h: f64,
    /// Initial time.
    pub t0: f64,
    /// Final time reached.
    pub t_end: f64,
    /// Steps taken.
    pub steps: usize,
    /// Final attitude R, row by row (9 numbers).
    pub attitude: Vec<f64>,
    /// Final attitude as a unit quaternion (w, x, y, z), w ≥ 0.
    pub quaternion: Vec<f64>,
    /// Final body angular velocity Ω.
    pub omega: Vec<f64>,
    /// Final body angular momentum Π.
    pub momentum: Vec<f64>,
    /// Final spatial angular momentum π = RΠ.
    pub spatial_momentum: Vec<f64>,
    /// Energy of the initial state.
    pub energy_initial: f64,
    /// Energy of the final state.
    pub energy_final: f64,
    /// Largest |E − E₀| over the step points (`None` if not asked for).
    pub energy_error_max: Option<f64>,
    /// Names of the conserved angular momenta (about the model's symmetry axes).
    pub momentum_names: Vec<&'static str>,
    /// Largest deviation of those angular momenta (`None` if the model has none or it was
    /// not asked for).
    pub momentum_error_max: Option<f64>,
    /// `momentum_error_max` relative to ‖Π₀‖.
    pub momentum_error_relative: Option<f64>,
    /// Names of the model's other invariants (body Casimirs).
    pub invariant_names: Vec<&'static str>,
    /// Largest deviation of those invariants (`None` if the model has none).
    pub invariant_error_max: Option<f64>,
    /// Largest ‖RᵀR − I‖_F over the step points (R is never re-orthonormalised).
    pub orthogonality_error_max: f64,
    /// ‖RᵀR − I‖_F at the end.
    pub orthogonality_error_final: f64,
    /// Newton iterations, summed over all steps.
    pub iterations: usize,
    /// Quadrature points at which derivatives of L were evaluated.
    pub evaluations: usize,
    /// Wall time of the integration, in seconds.
    pub seconds: f64,
    /// The trajectory file, if one was written.
    pub trajectory: Option<TrajectoryOutput>,
}

/// Comma-separated shortest round-trip values in brackets.
fn vector(values: &[f64]) -> String {
    let items: Vec<String> = values.iter().map(|x| Float(*x).to_string()).collect();
    format!("[{}]", items.join(", "))
}

/// `{:.3e}`, or `n/a` when absent.
fn error(value: Option<f64>) -> String {
    value.map_or_else(|| "n/a".into(), |x| format!("{x:.3e}"))
}

impl fmt::Display for RigidSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let parameters: Vec<String> = self
            .parameters
            .0
            .iter()
            .map(|(name, value)| format!("{name} = {value}"))
            .collect();
        let mut method = format!(
            "{} ({} form), {} CGL points, {} Gauss points; order {}",
            self.method, self.form, self.points, self.quadrature, self.order
        );
        if self.symmetric {
            method.push_str(", symmetric");
        }
        if self.symplectic {
            method.push_str(", symplectic");
        }
        let named = |value: Option<f64>, names: &[&str]| {
            if names.is_empty() {
                error(value)
            } else {
                format!("{} ({})", error(value), names.join(", "))
            }
        };
        let rows = [
            (
                "model".to_string(),
                format!("{} ({})", self.model, parameters.join(", ")),
            ),
            ("method".into(), method),
            ("step h".into(), Float(self.h).to_string()),
            (
                "time".into(),
                format!(
                    "{} to {} in {} steps",
                    Float(self.t0),
                    Float(self.t_end),
                    self.steps
                ),
            ),
            ("wall time".into(), format!("{:.3} s", self.seconds)),
            (
                "work".into(),
                format!(
                    "{} Newton iterations, {} evaluations",
                    self.iterations, self.evaluations
                ),
            ),
            ("final quaternion".into(), vector(&self.quaternion)),
            ("final omega".into(), vector(&self.omega)),
            ("final Pi (body)".into(), vector(&self.momentum)),
            ("final pi (space)".into(), vector(&self.spatial_momentum)),
            (
                "energy".into(),
                format!(
                    "{} to {}",
                    Float(self.energy_initial),
                    Float(self.energy_final)
                ),
            ),
            ("energy error".into(), error(self.energy_error_max)),
            (
                "momentum error".into(),
                named(self.momentum_error_max, &self.momentum_names),
            ),
            (
                "invariant error".into(),
                named(self.invariant_error_max, &self.invariant_names),
            ),
            (
                "|R^T R - I|".into(),
                format!(
                    "{:.3e} (max), {:.3e} (final)",
                    self.orthogonality_error_max, self.orthogonality_error_final
                ),
            ),
        ];
        for (label, value) in rows {
            writeln!(f, "{label:<18}{value}")?;
        }
        if let Some(trajectory) = &self.trajectory {
            writeln!(
                f,
                "{:<18}{} ({} rows, every {} steps)",
                "trajectory", trajectory.path, trajectory.rows, trajectory.every
            )?;
        }
        Ok(())
    }
}

/// Lines for `svi list`: the built-in rigid-body scenes and the rigid-body models.
pub fn list_lines() -> Vec<String> {
    let mut lines = vec!["Rigid-body scenes on SO(3) (svi run NAME; method lie-svi):".into()];
    for (name, text) in RIGID_SCENES {
        let description = text
            .lines()
            .next()
            .and_then(|line| line.strip_prefix('#'))
            .unwrap_or("")
            .trim();
        lines.push(format!("  {name:<18}{description}"));
    }
    lines.push(String::new());
    lines
        .push("Rigid-body models (model = \"NAME\"; parameters, default step and horizon):".into());
    for name in RIGID_MODEL_NAMES {
        if let Some(line) = visit_rigid_model(name, DescribeRigid) {
            lines.push(line);
        }
    }
    lines
}

/// Describes a rigid-body model in one line.
struct DescribeRigid;

impl RigidModelVisitor for DescribeRigid {
    type Output = String;
    fn visit<M: RigidZooModel>(self, model: M) -> String {
        let parameters: Vec<String> = model
            .parameters()
            .iter()
            .map(|(name, value)| format!("{name} = {}", Float(*value)))
            .collect();
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
        format!(
            "  {:<18}{}; h = {}, t_end = {}; {}",
            model.name(),
            parameters.join(", "),
            Float(model.default_step()),
            Float(model.default_horizon()),
            facts.join(", ")
        )
    }
}
