//! The summary of a run, for scenes on every space: what `svi run` prints, as text or as one
//! JSON object (`--json`).
//!
//! The JSON fields are an interface. Every summary has the fields of [`Summary`]; the final
//! state ([`StateSummary`]) and the conservation diagnostics ([`Conservation`]) are flattened
//! into it with the fields of their space. On ℝᴺ the run-mode fields (`retries`, `adapt`,
//! `tol`, `adaptivity`, `outputs`) are always present (`null` when unused); on SO(3) they
//! appear when the run uses them (recovery, adaptivity or output times), so a plain run
//! prints the fields it always has.

use std::fmt;

use serde::Serialize;

use crate::report::chaos::IndicatorSummary;
use crate::report::csv::{Float, Recorded, brief_vector as vector};
use crate::report::events::EventsSummary;
use crate::report::health::Warning;
use crate::report::schema::{Kind, Versioned};
use crate::report::sensitivity::SensitivitySummary;

/// The result of running a scene (`svi run --json` prints it as one JSON object).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Summary {
    /// Model name.
    pub model: String,
    /// Model parameters in effect.
    pub parameters: Parameters,
    /// Names of the configuration coordinates, the order of `q`, `v`, `p` (ℝᴺ only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub coordinates: Option<Vec<String>>,
    /// The method's name (see `svi::method::registry::METHODS`; its options are `points`
    /// and `quadrature`; on SO(3) `lie-svi`, with `form`).
    pub method: String,
    /// `full` or `reduced`: the form of the Lie-group integrator (SO(3) only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub form: Option<String>,
    /// Chebyshev–Gauss–Lobatto points (`None` for the classic methods).
    pub points: Option<usize>,
    /// Gauss–Legendre points (`None` for the methods without).
    pub quadrature: Option<usize>,
    /// Classical order of the method.
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
    /// The final state.
    #[serde(flatten)]
    pub state: StateSummary,
    /// Energy of the initial state.
    pub energy_initial: f64,
    /// Energy of the final state.
    pub energy_final: f64,
    /// Largest |E − E₀| over the step points (`None` if not asked for).
    pub energy_error_max: Option<f64>,
    /// |energy_final − energy_initial|.
    pub energy_error_final: f64,
    /// The energy's scale, max(|E₀|, ½|p₀·q̇₀|, ½|p·q̇|) at the two ends (Π·Ω on SO(3)):
    /// the health check warns when the energy error exceeds 1 % of it.
    pub energy_scale: f64,
    /// The conservation diagnostics of the space.
    #[serde(flatten)]
    pub conservation: Conservation,
    /// Nonlinear iterations, summed over all steps.
    pub iterations: usize,
    /// Points at which derivatives of the Lagrangian were evaluated.
    pub evaluations: usize,
    /// Jacobians of the nonlinear solves assembled and LU-factorised, summed over all steps
    /// (0 for explicit methods and fixed-point iterations).
    pub factorizations: usize,
    /// Failed steps retried with half the step (`recovery = "halve-step"`; see the module
    /// documentation for when it is present).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub retries: Option<usize>,
    /// Wall time of the integration, in seconds.
    pub seconds: f64,
    /// The trajectory file, if one was written.
    pub trajectory: Option<TrajectoryOutput>,
    /// Adaptivity and output times (see the module documentation for when it is present).
    #[serde(flatten)]
    pub solve: Option<SolveSummary>,
    /// `ok`, or `failed` for a run that stopped with an error (the fields above then describe
    /// the run up to its last good state) or failed the health check under `--strict`.
    pub status: Status,
    /// The health checks the run failed ([`crate::report::health`]).
    pub warnings: Vec<Warning>,
    /// Why the run failed (`status` = `failed`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<ErrorReport>,
    /// The trajectory kept in memory, for a scene that asks for it (`output.record`, the
    /// Python package) instead of a file; never printed.
    #[serde(skip)]
    pub recorded: Option<Recorded>,
    /// Every step's polynomial, with [`crate::OutputSection::dense`] (never serialised).
    #[serde(skip)]
    pub dense: Option<svi::stepping::dense::DenseOutput>,
    /// The events located and the Poincaré section (scenes with events or a section):
    /// `events`, `terminal_event`, `section`.
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub events: Option<EventsSummary>,
    /// The chaos indicators at the end of the run (`--indicators`): `megno`, `lyapunov_max`,
    /// `lyapunov`, `sali`, `gali`.
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub indicators: Option<IndicatorSummary>,
    /// The Jacobians of the state with respect to the initial state and parameters
    /// (`--sensitivity`): `sensitivity`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sensitivity: Option<SensitivitySummary>,
}

/// Whether a run ended well.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    /// The run reached its horizon.
    Ok,
    /// The run stopped with an error, or failed a health check under `--strict`.
    Failed,
}

/// A failure, for machine-readable output: the JSON `error` object.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ErrorReport {
    /// `invalid_parameter`, `non_convergence`, `singular_matrix`, `legendre_map`,
    /// `step_size_too_small`, `non_finite`, `diverged`, `too_many_steps` (the library's
    /// error kinds),
    /// `invalid_input` (other bad input), `output` (an output that cannot be written) or
    /// `health` (a failed health check under `--strict`).
    pub kind: &'static str,
    /// The message, as printed on stderr.
    pub message: String,
    /// Index of the failing step, for failures in a step.
    pub step: Option<usize>,
    /// Time of the failure (the start of the failing step).
    pub t: Option<f64>,
}

impl ErrorReport {
    /// The report of a library error: its kind, message, step and time.
    pub fn of(error: &svi::Error) -> Self {
        ErrorReport {
            kind: error.kind(),
            message: error.to_string(),
            step: error.step(),
            t: error.time(),
        }
    }
}

/// A state of a run (the final one, or one at an output time), with the fields of its space.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum StateSummary {
    /// On ℝᴺ.
    Vector {
        /// Configuration.
        q: Vec<f64>,
        /// Velocity.
        v: Vec<f64>,
        /// Momentum.
        p: Vec<f64>,
    },
    /// On SO(3).
    Rigid {
        /// Attitude R, row by row (9 numbers).
        attitude: Vec<f64>,
        /// Attitude as a unit quaternion (w, x, y, z), w ≥ 0.
        quaternion: Vec<f64>,
        /// Body angular velocity Ω.
        omega: Vec<f64>,
        /// Body angular momentum Π.
        momentum: Vec<f64>,
        /// Spatial angular momentum π = RΠ.
        spatial_momentum: Vec<f64>,
    },
    /// On a Lie group other than SO(3).
    Group {
        /// Configuration g, its stored entries (E numbers).
        g: Vec<f64>,
        /// Body velocity ξ.
        xi: Vec<f64>,
        /// Body momentum μ = ∂L/∂ξ.
        momentum: Vec<f64>,
        /// Spatial momentum Ad_{g⁻¹}ᵀμ.
        spatial_momentum: Vec<f64>,
    },
}

impl StateSummary {
    /// The configuration: q on ℝᴺ, the attitude's entries on SO(3).
    pub fn configuration(&self) -> &[f64] {
        match self {
            StateSummary::Vector { q, .. } => q,
            StateSummary::Rigid { attitude, .. } => attitude,
            StateSummary::Group { g, .. } => g,
        }
    }

    /// The configuration and velocity in words, for error messages.
    pub fn describe(&self) -> String {
        match self {
            StateSummary::Vector { q, v, .. } => format!("q = {}, v = {}", vector(q), vector(v)),
            StateSummary::Rigid {
                quaternion, omega, ..
            } => format!(
                "quaternion = {}, omega = {}",
                vector(quaternion),
                vector(omega)
            ),
            StateSummary::Group { g, xi, .. } => format!("g = {}, xi = {}", vector(g), vector(xi)),
        }
    }

    /// The rows of the text summary.
    fn rows(&self) -> Vec<(&'static str, String)> {
        match self {
            StateSummary::Vector { q, v, p } => vec![
                ("final q", vector(q)),
                ("final v", vector(v)),
                ("final p", vector(p)),
            ],
            StateSummary::Rigid {
                quaternion,
                omega,
                momentum,
                spatial_momentum,
                ..
            } => vec![
                ("final quaternion", vector(quaternion)),
                ("final omega", vector(omega)),
                ("final Pi (body)", vector(momentum)),
                ("final pi (space)", vector(spatial_momentum)),
            ],
            StateSummary::Group {
                g,
                xi,
                momentum,
                spatial_momentum,
            } => vec![
                ("final g", vector(g)),
                ("final xi", vector(xi)),
                ("final mu (body)", vector(momentum)),
                ("final mu (space)", vector(spatial_momentum)),
            ],
        }
    }

    /// One line for a state at an output time.
    fn line(&self) -> String {
        match self {
            StateSummary::Vector { q, v, p } => {
                format!("q {} v {} p {}", vector(q), vector(v), vector(p))
            }
            StateSummary::Rigid {
                quaternion,
                omega,
                momentum,
                ..
            } => format!(
                "quaternion {} omega {} Pi {}",
                vector(quaternion),
                vector(omega),
                vector(momentum)
            ),
            StateSummary::Group {
                g, xi, momentum, ..
            } => format!("g {} xi {} mu {}", vector(g), vector(xi), vector(momentum)),
        }
    }

    /// What the text summary calls the iterations of the method's solves.
    fn iterations(&self) -> &'static str {
        match self {
            StateSummary::Vector { .. } => "nonlinear",
            StateSummary::Rigid { .. } | StateSummary::Group { .. } => "Newton",
        }
    }
}

/// The conservation diagnostics of a run, with the fields of its space (`None`: not asked
/// for, or nothing to measure).
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum Conservation {
    /// On ℝᴺ.
    Vector {
        /// Largest deviation of the Noether momenta (`None` if the model has no symmetry).
        momentum_error_max: Option<f64>,
        /// Largest position error against the exact solution over the run (`None` if there
        /// is none, or the `solution` diagnostic was not asked for).
        solution_error_max: Option<f64>,
        /// Position error against the exact solution at the end (`None` if there is none).
        solution_error_final: Option<f64>,
    },
    /// On runtime-sized ℝⁿ (chains and lattices): no symmetry or exact solution is measured
    /// there (`momentum_error_max`, `solution_error_*` are always `None`, so the fields of
    /// ℝᴺ keep their meaning), and the model's invariants are.
    Local {
        /// Always `None` (no Noether momentum is measured on runtime-dimension models).
        momentum_error_max: Option<f64>,
        /// Always `None` (no exact solution).
        solution_error_max: Option<f64>,
        /// Always `None` (no exact solution).
        solution_error_final: Option<f64>,
        /// Names of the model's invariants (the Toda lattice's Lax traces).
        invariant_names: Vec<&'static str>,
        /// Largest absolute deviation of those invariants over the step points (`None` if
        /// the model has none or no diagnostic is asked for).
        invariant_error_max: Option<f64>,
    },
    /// On ℝᴺ with holonomic constraints g(q) = 0 (a constrained run): the fields of ℝᴺ
    /// (`solution_error_*` always `None`: no exact solution is known) and how well the run
    /// kept the constraints.
    Constrained {
        /// Largest deviation of the Noether momenta (`None` if the model has no symmetry).
        momentum_error_max: Option<f64>,
        /// Always `None` (no exact solution).
        solution_error_max: Option<f64>,
        /// Always `None` (no exact solution).
        solution_error_final: Option<f64>,
        /// The constraints, as written.
        constraints: Vec<String>,
        /// Largest |g(q)|∞ over the step points (`None` for a run that failed before its end).
        constraint_error_max: Option<f64>,
        /// Largest |G(q) q̇|∞ over the step points, G = ∂g/∂q (the hidden velocity
        /// constraint; `None` for a run that failed before its end).
        velocity_constraint_error_max: Option<f64>,
        /// |q − q₀|: how far the projection of the initial state onto g = 0 moved q₀.
        initial_q_moved: f64,
        /// |p − p₀|: how far the projection onto the cotangent space G M⁻¹ p = 0 moved p₀.
        initial_p_moved: f64,
    },
    /// On SO(3).
    Rigid {
        /// Names of the conserved angular momenta (about the model's symmetry axes).
        momentum_names: Vec<&'static str>,
        /// Largest deviation of those angular momenta (`None` if the model has none).
        momentum_error_max: Option<f64>,
        /// `momentum_error_max` relative to ‖Π₀‖.
        momentum_error_relative: Option<f64>,
        /// Names of the model's other invariants (body Casimirs).
        invariant_names: Vec<&'static str>,
        /// Largest deviation of those invariants (`None` if the model has none).
        invariant_error_max: Option<f64>,
        /// Largest ‖RᵀR − I‖_F over the step points (R is never re-orthonormalised).
        orthogonality_error_max: Option<f64>,
        /// ‖RᵀR − I‖_F at the end.
        orthogonality_error_final: f64,
    },
    /// On a Lie group other than SO(3).
    Group {
        /// Names of the Noether momenta of the model's symmetry generators.
        momentum_names: Vec<&'static str>,
        /// Largest deviation of those momenta (`None` if the model has none).
        momentum_error_max: Option<f64>,
        /// `momentum_error_max` relative to the size of the initial spatial momentum.
        momentum_error_relative: Option<f64>,
        /// Largest ‖g − g_exact‖ over the step points (`None` without an exact solution or
        /// the `solution` diagnostic).
        solution_error_max: Option<f64>,
        /// ‖g − g_exact‖ at the end (`None` without an exact solution).
        solution_error_final: Option<f64>,
        /// Largest distance of the configuration from the group over the step points
        /// (‖RᵀR − I‖_F of each rotation factor, never re-projected).
        group_defect_max: Option<f64>,
        /// That distance at the end.
        group_defect_final: f64,
    },
}

impl Conservation {
    /// Largest deviation of the conserved momenta (Noether momenta on ℝᴺ, angular momenta
    /// about the symmetry axes on SO(3)).
    pub fn momentum_error_max(&self) -> Option<f64> {
        match self {
            Conservation::Vector {
                momentum_error_max, ..
            }
            | Conservation::Local {
                momentum_error_max, ..
            }
            | Conservation::Constrained {
                momentum_error_max, ..
            }
            | Conservation::Rigid {
                momentum_error_max, ..
            }
            | Conservation::Group {
                momentum_error_max, ..
            } => *momentum_error_max,
        }
    }

    /// Every measured number, by its JSON name (for the check that none is non-finite).
    pub fn numbers(&self) -> Vec<(&'static str, Option<f64>)> {
        let mut numbers = vec![
            ("momentum_error_max", self.momentum_error_max()),
            ("solution_error_max", self.solution_error_max()),
            ("solution_error_final", self.solution_error_final()),
        ];
        match self {
            Conservation::Vector { .. } => {}
            Conservation::Local {
                invariant_error_max,
                ..
            } => numbers.push(("invariant_error_max", *invariant_error_max)),
            Conservation::Constrained {
                constraint_error_max,
                velocity_constraint_error_max,
                initial_q_moved,
                initial_p_moved,
                ..
            } => numbers.extend([
                ("constraint_error_max", *constraint_error_max),
                (
                    "velocity_constraint_error_max",
                    *velocity_constraint_error_max,
                ),
                ("initial_q_moved", Some(*initial_q_moved)),
                ("initial_p_moved", Some(*initial_p_moved)),
            ]),
            Conservation::Rigid {
                momentum_error_relative,
                invariant_error_max,
                orthogonality_error_max,
                orthogonality_error_final,
                ..
            } => numbers.extend([
                ("momentum_error_relative", *momentum_error_relative),
                ("invariant_error_max", *invariant_error_max),
                ("orthogonality_error_max", *orthogonality_error_max),
                (
                    "orthogonality_error_final",
                    Some(*orthogonality_error_final),
                ),
            ]),
            Conservation::Group {
                momentum_error_relative,
                group_defect_max,
                group_defect_final,
                ..
            } => numbers.extend([
                ("momentum_error_relative", *momentum_error_relative),
                ("group_defect_max", *group_defect_max),
                ("group_defect_final", Some(*group_defect_final)),
            ]),
        }
        numbers
    }

    /// Largest position error against the exact solution (ℝᴺ; `None` on SO(3)).
    pub fn solution_error_max(&self) -> Option<f64> {
        match self {
            Conservation::Vector {
                solution_error_max, ..
            }
            | Conservation::Local {
                solution_error_max, ..
            }
            | Conservation::Constrained {
                solution_error_max, ..
            }
            | Conservation::Group {
                solution_error_max, ..
            } => *solution_error_max,
            Conservation::Rigid { .. } => None,
        }
    }

    /// Position error against the exact solution at the end (ℝᴺ; `None` on SO(3)).
    pub fn solution_error_final(&self) -> Option<f64> {
        match self {
            Conservation::Vector {
                solution_error_final,
                ..
            }
            | Conservation::Local {
                solution_error_final,
                ..
            }
            | Conservation::Constrained {
                solution_error_final,
                ..
            }
            | Conservation::Group {
                solution_error_final,
                ..
            } => *solution_error_final,
            Conservation::Rigid { .. } => None,
        }
    }

    /// The rows of the text summary.
    fn rows(&self) -> Vec<(&'static str, String)> {
        let named = |value: Option<f64>, names: &[&str]| {
            if names.is_empty() {
                error(value)
            } else {
                format!("{} ({})", error(value), names.join(", "))
            }
        };
        match self {
            Conservation::Vector {
                momentum_error_max,
                solution_error_max,
                solution_error_final,
            } => vec![
                ("momentum error", error(*momentum_error_max)),
                (
                    "solution error",
                    solution_row(*solution_error_max, *solution_error_final),
                ),
            ],
            Conservation::Local {
                invariant_names,
                invariant_error_max,
                ..
            } => vec![(
                "invariant error",
                named(*invariant_error_max, invariant_names),
            )],
            Conservation::Constrained {
                momentum_error_max,
                constraints,
                constraint_error_max,
                velocity_constraint_error_max,
                initial_q_moved,
                initial_p_moved,
                ..
            } => vec![
                ("momentum error", error(*momentum_error_max)),
                ("constraints", constraints.join("; ")),
                (
                    "constraint error",
                    format!(
                        "|g| {} max, |G q'| {} max",
                        error(*constraint_error_max),
                        error(*velocity_constraint_error_max)
                    ),
                ),
                (
                    "initial projection",
                    format!("q moved {initial_q_moved:.3e}, p moved {initial_p_moved:.3e}"),
                ),
            ],
            Conservation::Rigid {
                momentum_names,
                momentum_error_max,
                invariant_names,
                invariant_error_max,
                orthogonality_error_max,
                orthogonality_error_final,
                ..
            } => vec![
                ("momentum error", named(*momentum_error_max, momentum_names)),
                (
                    "invariant error",
                    named(*invariant_error_max, invariant_names),
                ),
                (
                    "|R^T R - I|",
                    format!(
                        "{} (max), {:.3e} (final)",
                        error(*orthogonality_error_max),
                        orthogonality_error_final
                    ),
                ),
            ],
            Conservation::Group {
                momentum_names,
                momentum_error_max,
                solution_error_max,
                solution_error_final,
                group_defect_max,
                group_defect_final,
                ..
            } => vec![
                ("momentum error", named(*momentum_error_max, momentum_names)),
                (
                    "solution error",
                    solution_row(*solution_error_max, *solution_error_final),
                ),
                (
                    "group defect",
                    format!(
                        "{} (max), {:.3e} (final)",
                        error(*group_defect_max),
                        group_defect_final
                    ),
                ),
            ],
        }
    }
}

/// The text summary's solution error: its largest value and its value at the end, as known.
fn solution_row(max: Option<f64>, last: Option<f64>) -> String {
    match (max, last) {
        (Some(max), Some(last)) => format!("{max:.3e} max, {last:.3e} at the end"),
        (None, Some(last)) => format!("{last:.3e} at the end"),
        (max, None) => error(max),
    }
}

/// Adaptivity and output times of a run.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SolveSummary {
    /// Adaptivity mode: `none`, `step`, `degree` or `reparam`.
    pub adapt: &'static str,
    /// The monitor of `reparam` (e.g. `sundman:1.5`); `None` for the other modes.
    pub monitor: Option<String>,
    /// Target final error of the adaptive modes.
    pub tol: Option<f64>,
    /// What the adaptivity did (adaptive runs and runs with output times).
    pub adaptivity: Option<AdaptivitySummary>,
    /// The states at the requested output times (`None` without output times).
    pub outputs: Option<Vec<OutputPoint>>,
}

/// A state at a requested output time.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OutputPoint {
    /// Time.
    pub t: f64,
    /// The state, with the fields of its space.
    #[serde(flatten)]
    pub state: StateSummary,
}

/// What [`svi::solve()`] did, for the summary.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AdaptivitySummary {
    /// Accepted steps.
    pub accepted: usize,
    /// Rejected trial steps.
    pub rejected: usize,
    /// Smallest accepted step.
    pub min_step: f64,
    /// Largest accepted step.
    pub max_step: f64,
    /// (CGL points, steps that used them).
    pub points_used: Vec<(usize, usize)>,
    /// Steps of `adapt = "degree"` that missed the tolerance at `max_points`.
    pub unmet: usize,
    /// States reported at output times.
    pub outputs: usize,
}

/// Model parameters in the model's order (serialised as a JSON object).
#[derive(Debug, Clone, PartialEq)]
pub struct Parameters(pub Vec<(&'static str, f64)>);

impl fmt::Display for Parameters {
    /// `name = value, …` in the model's order, each value as [`Float`] writes it (1e-300, not
    /// its 300 digits).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, (name, value)) in self.0.iter().enumerate() {
            let separator = if i == 0 { "" } else { ", " };
            write!(f, "{separator}{name} = {}", Float(*value))?;
        }
        Ok(())
    }
}

impl Serialize for Parameters {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut map = serializer.serialize_map(Some(self.0.len()))?;
        for (name, value) in &self.0 {
            map.serialize_entry(name, value)?;
        }
        map.end()
    }
}

/// Where the trajectory went.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TrajectoryOutput {
    /// The CSV file.
    pub path: String,
    /// Thinning factor.
    pub every: usize,
    /// Data rows written (the initial point, every `every`-th step, and the last point; or
    /// the initial point and the output times).
    pub rows: usize,
}

/// `{:.3e}`, or `n/a` when absent.
fn error(value: Option<f64>) -> String {
    value.map_or_else(|| "n/a".into(), |x| format!("{x:.3e}"))
}

impl Summary {
    /// The method line of the text summary: name, form, points, order and properties.
    fn method_line(&self) -> String {
        let mut method = self.method.clone();
        if let Some(form) = &self.form {
            method.push_str(&format!(" ({form} form)"));
        }
        if let Some(points) = self.points {
            method.push_str(&format!(", {points} CGL points"));
        }
        if let Some(quadrature) = self.quadrature {
            method.push_str(&format!(", {quadrature} Gauss points"));
        }
        method.push_str(&format!("; order {}", self.order));
        if self.symmetric {
            method.push_str(", symmetric");
        }
        if self.symplectic {
            method.push_str(", symplectic");
        }
        method
    }

    /// The adaptivity line of the text summary.
    fn adaptivity_line(solve: &SolveSummary, a: &AdaptivitySummary) -> String {
        let mut line = format!(
            "{} accepted, {} rejected steps, h from {:.3e} to {:.3e}",
            a.accepted, a.rejected, a.min_step, a.max_step
        );
        if let Some(tol) = solve.tol {
            line = format!("{}, tol {tol:e}: {line}", solve.adapt);
        }
        if let Some(monitor) = &solve.monitor {
            line = format!("{}, monitor {monitor}: {line}", solve.adapt);
        }
        if solve.adapt == "step" && a.unmet > 0 {
            line.push_str(&format!(
                "; {} steps at the resolution of the error estimate",
                a.unmet
            ));
        }
        if solve.adapt == "degree" {
            let used: Vec<String> = a
                .points_used
                .iter()
                .map(|(points, steps)| format!("{points}:{steps}"))
                .collect();
            line.push_str(&format!("; points:steps {}", used.join(" ")));
            if a.unmet > 0 {
                line.push_str(&format!("; {} steps missed tol at max_points", a.unmet));
            }
        }
        line
    }
}

impl fmt::Display for Summary {
    /// An aligned block of labelled lines, the labels as wide as the longest plus two.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let retries = match self.retries {
            Some(retries) if retries > 0 => format!(", {retries} steps retried with h/2"),
            _ => String::new(),
        };
        let mut rows = vec![
            ("model", format!("{} ({})", self.model, self.parameters)),
            ("method", self.method_line()),
            ("step h", Float(self.h).to_string()),
            (
                "time",
                format!(
                    "{} to {} in {} steps",
                    Float(self.t0),
                    Float(self.t_end),
                    self.steps
                ),
            ),
            ("wall time", format!("{:.3} s", self.seconds)),
            (
                "work",
                format!(
                    "{} {} iterations, {} evaluations{retries}",
                    self.iterations,
                    self.state.iterations(),
                    self.evaluations
                ),
            ),
        ];
        if let Some(coordinates) = &self.coordinates {
            rows.push(("coordinates", coordinates.join(", ")));
        }
        rows.extend(self.state.rows());
        rows.push((
            "energy",
            format!(
                "{} to {}",
                Float(self.energy_initial),
                Float(self.energy_final)
            ),
        ));
        rows.push(("energy error", error(self.energy_error_max)));
        rows.extend(self.conservation.rows());
        let events = self.events.as_ref().map(EventsSummary::rows);
        rows.extend(events.into_iter().flatten());
        let indicators = self.indicators.as_ref().map(IndicatorSummary::rows);
        rows.extend(indicators.into_iter().flatten());
        let sensitivity = self.sensitivity.as_ref().map(SensitivitySummary::rows);
        rows.extend(sensitivity.into_iter().flatten());
        let width = rows.iter().map(|(label, _)| label.len()).max().unwrap_or(0) + 2;
        for (label, value) in rows {
            writeln!(f, "{label:<width$}{value}")?;
        }
        if let Some(solve) = &self.solve {
            if let Some(adaptivity) = &solve.adaptivity {
                let line = Summary::adaptivity_line(solve, adaptivity);
                writeln!(f, "{:<width$}{line}", "adaptivity")?;
            }
            for point in solve.outputs.iter().flatten() {
                let label = format!("t = {}", Float(point.t));
                writeln!(f, "{label:<width$}{}", point.state.line())?;
            }
        }
        if let Some(trajectory) = &self.trajectory {
            writeln!(
                f,
                "{:<width$}{} ({} rows, every {} steps)",
                "trajectory", trajectory.path, trajectory.rows, trajectory.every
            )?;
        }
        Ok(())
    }
}

impl Versioned for Summary {
    fn kind(&self) -> Kind {
        match self.state {
            StateSummary::Vector { .. } => Kind::Ode,
            StateSummary::Rigid { .. } | StateSummary::Group { .. } => Kind::LieGroup,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parameters_read_as_name_value_pairs_with_short_numbers() {
        let parameters = Parameters(vec![("e", 0.9), ("mu", 1.0), ("omega", 1e-300)]);
        assert_eq!(parameters.to_string(), "e = 0.9, mu = 1, omega = 1e-300");
        assert_eq!(Parameters(Vec::new()).to_string(), "");
    }
}
