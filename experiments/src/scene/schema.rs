//! The sections of a scene file, as deserialised from TOML: `[initial]`, `[method]`, `[run]`,
//! `[output]`, and the named choices in them (adaptivity, recovery, diagnostics, form).
//!
//! One schema serves scenes on every space; the fields of `[initial]` and `form` of `[method]`
//! that belong to the other space are rejected by the scene's checks
//! ([`crate::scene::Scene::check`]).

use std::path::PathBuf;
use std::str::FromStr;

use serde::Deserialize;
use svi::solve::Adapt;
use svi::{Recovery, RunOptions};

use crate::scene::method::SceneMethod;

/// A diagnostic evaluated at every step point.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, clap::ValueEnum)]
#[serde(try_from = "String")]
pub enum Diagnostic {
    /// Largest energy deviation |E − E₀|.
    Energy,
    /// Largest deviation of the Noether momenta.
    Momentum,
    /// Largest position error against the exact solution.
    Solution,
    /// No diagnostic at all (alone; on SO(3) also no invariant and orthogonality errors).
    None,
}

impl Diagnostic {
    /// The names, as written in scenes and on the command line.
    pub const NAMES: [&'static str; 4] = ["energy", "momentum", "solution", "none"];
}

/// A diagnostic name that is not one of [`Diagnostic::NAMES`].
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown diagnostic '{name}' (known: {})", Diagnostic::NAMES.join(", "))]
pub struct UnknownDiagnostic {
    /// The name asked for.
    pub name: String,
}

impl FromStr for Diagnostic {
    type Err = UnknownDiagnostic;
    fn from_str(name: &str) -> Result<Self, UnknownDiagnostic> {
        match name {
            "energy" => Ok(Diagnostic::Energy),
            "momentum" => Ok(Diagnostic::Momentum),
            "solution" => Ok(Diagnostic::Solution),
            "none" => Ok(Diagnostic::None),
            _ => Err(UnknownDiagnostic { name: name.into() }),
        }
    }
}

impl TryFrom<String> for Diagnostic {
    type Error = UnknownDiagnostic;
    fn try_from(name: String) -> Result<Self, UnknownDiagnostic> {
        name.parse()
    }
}

/// An initial vector on ℝᴺ: its components, or — for a chain — an expression in the site
/// index `i` (from 1) and the parameters, evaluated at every site (`q = "A*sin(pi*i/(n+1))"`),
/// or one such expression per family of a chain written with several (`["0", "0.1*i"]`).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(untagged)]
pub enum Components {
    /// The components.
    Values(Vec<f64>),
    /// One expression for every site (a chain of one family).
    Expression(String),
    /// One expression per family, for every site.
    Expressions(Vec<String>),
}

impl Components {
    /// The expressions, one per family, if the components are given by expressions.
    pub fn expressions(&self) -> Option<Vec<String>> {
        match self {
            Components::Values(_) => None,
            Components::Expression(text) => Some(vec![text.clone()]),
            Components::Expressions(texts) => Some(texts.clone()),
        }
    }
}

/// The boundary rule of a chain written as text, as named in scenes (see
/// [`svi::model::text::Boundary`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum BoundaryName {
    /// Indices outside 1..n read zero.
    Fixed,
    /// Indices wrap modulo n.
    Periodic,
}

impl From<BoundaryName> for svi::model::text::Boundary {
    fn from(name: BoundaryName) -> Self {
        match name {
            BoundaryName::Fixed => svi::model::text::Boundary::Fixed,
            BoundaryName::Periodic => svi::model::text::Boundary::Periodic,
        }
    }
}

/// `[initial]`: on ℝᴺ t0, q and one of v, p; on SO(3) t0, one of rotation, quaternion and
/// one of omega, momentum. Absent fields come from the model's default state.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InitialSection {
    /// Initial time.
    pub t0: Option<f64>,
    /// Initial configuration (ℝᴺ).
    pub q: Option<Components>,
    /// Initial velocity (ℝᴺ; excludes `p`).
    pub v: Option<Components>,
    /// Initial momentum (ℝᴺ; excludes `v`).
    pub p: Option<Components>,
    /// R₀ as a rotation vector, R₀ = exp(rotation^) (SO(3); excludes `quaternion`).
    pub rotation: Option<Vec<f64>>,
    /// R₀ as a unit quaternion (w, x, y, z) (SO(3); excludes `rotation`).
    pub quaternion: Option<Vec<f64>>,
    /// Body angular velocity Ω₀ (SO(3); excludes `momentum`).
    pub omega: Option<Vec<f64>>,
    /// Body angular momentum Π₀ (SO(3); excludes `omega`), or body momentum μ₀ on another
    /// group (excludes `xi`).
    pub momentum: Option<Vec<f64>>,
    /// g₀ as its stored entries (a group other than SO(3); excludes `log`).
    pub g: Option<Vec<f64>>,
    /// g₀ = exp(log) (a group other than SO(3); excludes `g`).
    pub log: Option<Vec<f64>>,
    /// Body velocity ξ₀ (a group other than SO(3); excludes `momentum`).
    pub xi: Option<Vec<f64>>,
}

/// `[method]`: name and options.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MethodSection {
    /// The method, `name`, `name:P` or `name:P/M` of `svi::method::registry::METHODS`
    /// (default: `svi` on ℝᴺ, `lie-svi` on SO(3)), or for a scene with constraints a
    /// constrained method (default `rattle`; see [`crate::scene::constrained`]).
    #[serde(default)]
    pub name: Option<SceneMethod>,
    /// Chebyshev–Gauss–Lobatto points of svi, sc and lie-svi, applied on top of `name`
    /// (default: the method's); ignored by the methods without.
    pub points: Option<usize>,
    /// Gauss–Legendre points of svi and lie-svi, applied on top of `name` (default: svi
    /// 2 × points, lie-svi points); ignored by the other methods.
    pub quadrature: Option<usize>,
    /// The form of the Lie-group integrator (SO(3) only; default full; `lie-svi-reduced` is
    /// `reduced`).
    pub form: Option<FormName>,
}

/// The form of the Lie-group integrator, as named in scenes and on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum FormName {
    /// The full discrete Euler–Lagrange equations on SO(3) (Leok 2004 §5.3).
    Full,
    /// The discrete Euler–Poincaré equations (§5.4), for G-invariant Lagrangians.
    Reduced,
}

/// `[run]`: step, horizon, adaptivity and failure handling.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunSection {
    /// Step size (default: the model's default step); unused by `adapt = "step"`, which
    /// chooses its first step from the initial state.
    pub h: Option<f64>,
    /// Final time (default: the model's default horizon).
    pub t_end: Option<f64>,
    /// Adaptivity (default none).
    pub adapt: Option<AdaptMode>,
    /// Target final error of `adapt = "step"` and `adapt = "degree"`.
    pub tol: Option<f64>,
    /// The monitor g(q) of `adapt = "reparam"` (dt = g dτ), as
    /// [`svi::model::reparametrized::MonitorSpec`] parses it, e.g. `"sundman:1.5"`
    /// (default) or `"force:0.75"`.
    pub monitor: Option<String>,
    /// Fewest CGL points of `adapt = "degree"` (default 3).
    pub min_points: Option<usize>,
    /// Most CGL points of `adapt = "degree"` (default 24).
    pub max_points: Option<usize>,
    /// What to do when a step fails (default: `none`, stop with the error).
    pub recovery: Option<RecoveryKind>,
    /// Successive halvings allowed by `recovery = "halve-step"` (default
    /// [`DEFAULT_MAX_HALVINGS`]).
    pub max_halvings: Option<usize>,
    /// Stop with an error once a state component exceeds this in absolute value (default:
    /// no limit; NaN and infinity always stop the run).
    pub divergence_limit: Option<f64>,
    /// Most steps of the run, 1 to [`svi::stepping::grid::MAX_STEPS`] (the default): an
    /// adaptive run that needs more stops with `too_many_steps` (the run so far reported);
    /// a fixed-step run that needs more is rejected before it starts.
    pub max_steps: Option<usize>,
    /// Chaos indicators computed from the method's exact tangent maps along the run
    /// ([`svi::analysis::chaos`]; fixed steps on ℝᴺ): the summary's `megno`, `lyapunov_max`,
    /// `lyapunov`, `sali` and `gali`.
    pub indicators: Option<Vec<Indicator>>,
    /// Derivatives of the state with respect to the initial state and the model's parameters
    /// ([`svi::analysis::sensitivity`]; fixed steps, models of
    /// [`svi_models::PARAMETRIC_MODEL_NAMES`]): `q0`, `v0` (`p0` for a start given in
    /// momenta) and parameter names, in the order of the summary's `sensitivity.columns`.
    pub sensitivity: Option<Vec<String>>,
    /// Every how many steps the sensitivities are reported besides the start and the end
    /// (default: only those two).
    pub sensitivity_every: Option<usize>,
}

/// A chaos indicator of a run, as named in scenes and on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Indicator {
    /// MEGNO ⟨Y⟩ at the end (→ 2 on regular orbits, grows as λt/2 on chaotic ones): `megno`.
    Megno,
    /// The maximal Lyapunov exponent, one deviation vector renormalised: `lyapunov_max`.
    Lyapunov,
    /// The full Lyapunov spectrum, 2N exponents by QR re-orthonormalisation: `lyapunov`.
    Spectrum,
    /// The smaller alignment index of two deviation vectors (→ 0 on chaotic orbits): `sali`.
    Sali,
    /// GALI of order N, the volume of N unit deviation vectors (about constant on regular
    /// orbits, → 0 exponentially on chaotic ones; 1 for N = 1): `gali`.
    Gali,
}

impl Indicator {
    /// The names, as written in scenes and on the command line.
    pub const NAMES: [&'static str; 5] = ["megno", "lyapunov", "spectrum", "sali", "gali"];

    /// Every indicator, in the order of their summary fields and table columns.
    pub const ALL: [Indicator; 5] = [
        Indicator::Megno,
        Indicator::Lyapunov,
        Indicator::Spectrum,
        Indicator::Sali,
        Indicator::Gali,
    ];

    /// The ensemble table's columns of the indicator on a phase space of `dimension` (2N):
    /// (column, summary field, component of an array field).
    pub fn columns(self, dimension: usize) -> Vec<(String, &'static str, Option<usize>)> {
        match self {
            Indicator::Megno => vec![("megno".into(), "megno", None)],
            Indicator::Lyapunov => vec![("lyapunov_max".into(), "lyapunov_max", None)],
            Indicator::Spectrum => (0..dimension)
                .map(|i| (format!("lyapunov_{}", i + 1), "lyapunov", Some(i)))
                .collect(),
            Indicator::Sali => vec![("sali".into(), "sali", None)],
            Indicator::Gali => vec![("gali".into(), "gali", None)],
        }
    }
}

/// The adaptivity modes of [`svi::solve()`], as named in scenes and on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum AdaptMode {
    /// Fixed step.
    #[default]
    None,
    /// Step doubling to meet `tol`.
    Step,
    /// Points per step (svi, sc and lie-svi) to meet `tol`, at fixed step.
    Degree,
    /// Fixed steps `h` in computational time τ, physical steps dt = g(q) dτ from a monitor
    /// (structure-preserving; models on ℝᴺ without time dependence or force).
    Reparam,
    /// Symplectic-energy-momentum steps: each step's size fixed by discrete energy
    /// conservation, the first of size `h` (svi on models on ℝᴺ without time dependence or
    /// force).
    Sem,
}

impl AdaptMode {
    /// The name, as written in scenes and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            AdaptMode::None => "none",
            AdaptMode::Step => "step",
            AdaptMode::Degree => "degree",
            AdaptMode::Reparam => "reparam",
            AdaptMode::Sem => "sem",
        }
    }
}

impl From<AdaptMode> for Adapt {
    fn from(mode: AdaptMode) -> Adapt {
        match mode {
            AdaptMode::None => Adapt::None,
            AdaptMode::Step => Adapt::Step,
            AdaptMode::Degree => Adapt::Degree,
            // Fixed steps, in τ.
            AdaptMode::Reparam => Adapt::None,
            AdaptMode::Sem => Adapt::Sem,
        }
    }
}

/// Successive halvings of a failed step allowed by default under `recovery = "halve-step"`.
pub const DEFAULT_MAX_HALVINGS: usize = 4;

/// A scene's recovery policy for failed steps (`[run] recovery`, `--recovery`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum RecoveryKind {
    /// Stop the run with the failed step's error.
    #[default]
    None,
    /// Retry a failed step as two half steps (recursively), then go on with the original
    /// step.
    HalveStep,
}

impl RunSection {
    /// The library's run options for this section.
    pub fn options(&self) -> Result<RunOptions, svi::Error> {
        let mut options = RunOptions::default();
        match (self.recovery.unwrap_or_default(), self.max_halvings) {
            (RecoveryKind::None, Some(_)) => {
                return Err(svi::Error::invalid(
                    "max_halvings",
                    "set, but recovery is not \"halve-step\"",
                ));
            }
            (RecoveryKind::None, None) => {}
            (RecoveryKind::HalveStep, halvings) => {
                options = options.with_recovery(Recovery::HalveStep {
                    max_halvings: halvings.unwrap_or(DEFAULT_MAX_HALVINGS),
                });
            }
        }
        if let Some(limit) = self.divergence_limit {
            options = options.with_divergence_limit(limit);
        }
        options.validate()?;
        Ok(options)
    }
}

/// `[output]`: trajectory file, output times and diagnostics.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputSection {
    /// Write every `every`-th step of the trajectory (default 1; needs `trajectory`, and no
    /// `output_times`).
    pub every: Option<usize>,
    /// CSV file for the trajectory: the initial point and every `every`-th step, or with
    /// `output_times` the initial point and the states at those times (absent: no
    /// trajectory is kept).
    pub trajectory: Option<PathBuf>,
    /// SVG file for a line chart of the trajectory file's columns against t (needs
    /// `trajectory`; absent: no plot).
    pub plot: Option<PathBuf>,
    /// Diagnostics to compute (default: [`Scene::DEFAULT_DIAGNOSTICS`](crate::Scene::DEFAULT_DIAGNOSTICS),
    /// energy and momentum; `["none"]` or `[]`: none at all).
    pub diagnostics: Option<Vec<Diagnostic>>,
    /// Report the states at these times, read off each step's polynomial (dense output).
    pub output_times: Option<Vec<f64>>,
    /// Add the Lagrange multipliers λ of a constrained run to the trajectory, one column
    /// `lambda_1`, … per constraint (default false; needs `trajectory`).
    pub multipliers: Option<bool>,
    /// A Poincaré section, `"y=0,vy>0"` ([`crate::scene::events`]): the trajectory file
    /// holds the section's points instead of the steps, and `plot` draws them.
    pub section: Option<crate::scene::events::SectionSpec>,
    /// CSV file for the located events (needs events): one row per event, `event,t,q_…,v_…,p_…`,
    /// written after the run, a failed one included.
    pub events: Option<PathBuf>,
    /// Keep the trajectory in memory (the summary's `recorded`) instead of writing a file:
    /// the Python package's runs, which never touch the file system. `every` and
    /// `output_times` apply as to a file. Not a scene field.
    #[serde(skip)]
    pub record: bool,
    /// Keep every step's polynomial (the summary's `dense`,
    /// [`svi::solve::SolveOptions::dense`]) so that the solution can be evaluated at any
    /// time afterwards: the Python package's `Solution(t)`. Not a scene field.
    #[serde(skip)]
    pub dense: bool,
}
