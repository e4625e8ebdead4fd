//! The health check of a run: a run that completes is not yet a run to trust. Two symptoms
//! of garbage are checked after every run, at no cost to the run itself:
//!
//! - **energy**: for a model whose energy is conserved (autonomous, unforced), the energy
//!   error (the largest over the step points when measured, otherwise that of the final
//!   point; the warning says which) above [`ENERGY_TOLERANCE`] of the energy's scale, the
//!   largest of |E₀|, ½|p₀·q̇₀| and ½|p·q̇| at the end (the energy, and the kinetic energy of
//!   a quadratic kinetic term at both ends, Π·Ω on SO(3): E₀ alone may vanish, as for a
//!   double pendulum released from rest with its arms horizontal);
//! - **escape**: the configuration's largest component grown beyond [`ESCAPE_FACTOR`] times
//!   its initial size (at least 1): a bound motion that flew off (on ℝᴺ).
//!
//! - **non-finite diagnostics** ([`non_finite`]): a diagnostic that came out NaN or infinite
//!   (an invariant that overflows while the state does not) means nothing; JSON would print
//!   it as `null`, the mark of a diagnostic not measured;
//! - **fields** ([`check_field`], pseudospectral runs): the discrete norm, the energy and the
//!   error against the exact solution, each above [`ENERGY_TOLERANCE`] of its scale.
//!
//! A failing check is a [`Warning`]: printed on stderr as `warning: …`, listed in the JSON
//! summary's `warnings`, and with `svi run --strict` an error (exit status 1). A run that
//! recovered failed steps and then fails a check says so.

use serde::Serialize;

/// Largest energy error accepted, relative to the energy's scale: 1 %.
pub const ENERGY_TOLERANCE: f64 = 1e-2;

/// Largest growth of the configuration accepted (final largest component over the initial
/// one, or 1 if that is smaller): 100.
pub const ESCAPE_FACTOR: f64 = 1e2;

/// A check the run failed.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Warning {
    /// `energy` or `escape`.
    pub kind: &'static str,
    /// What was measured, against what bound, and what it means.
    pub message: String,
}

/// What the checks look at.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Measured {
    /// Whether the model conserves energy (autonomous and unforced).
    pub conserves_energy: bool,
    /// Energy of the initial point.
    pub energy_initial: f64,
    /// Energy of the final point.
    pub energy_final: f64,
    /// Largest |E − E₀| over the step points, if measured.
    pub energy_error_max: Option<f64>,
    /// The energy's scale: the largest of |E₀|, ½|p₀·q̇₀| and ½|p·q̇| at the end.
    pub energy_scale: f64,
    /// Largest component of the initial and the final configuration (ℝᴺ only).
    pub extent: Option<(f64, f64)>,
    /// Failed steps retried with half the step.
    pub retries: usize,
}

/// The checks `measured` fails.
pub fn check(measured: &Measured) -> Vec<Warning> {
    let mut warnings = Vec::new();
    let error = measured
        .energy_error_max
        .unwrap_or((measured.energy_final - measured.energy_initial).abs());
    let scale = measured.energy_scale;
    // NaN compares false: a NaN error or scale is never healthy.
    let healthy = matches!(
        error.partial_cmp(&(ENERGY_TOLERANCE * scale)),
        Some(std::cmp::Ordering::Less | std::cmp::Ordering::Equal)
    );
    if measured.conserves_energy && !healthy {
        let relative = if scale > 0.0 {
            error / scale
        } else {
            f64::INFINITY
        };
        // Which error it is: the largest over the step points, or (not observed at every
        // step) that of the final point alone.
        let what = match measured.energy_error_max {
            Some(_) => "the largest energy error over the run",
            None => "the final energy error (the energy was not observed at every step)",
        };
        let message = if error.is_finite() && scale.is_finite() {
            format!(
                "{what}, {error:.3e}, is {:.3} % of the energy's scale {scale:.3e} (more than \
                 {} %): the step does not resolve the motion, and the result is not to be \
                 trusted",
                100.0 * relative,
                100.0 * ENERGY_TOLERANCE
            )
        } else {
            format!(
                "{what} is not finite (the state overflows the energy): the result is not to be \
                 trusted"
            )
        };
        warnings.push(Warning {
            kind: "energy",
            message,
        });
    }
    if let Some((initial, last)) = measured.extent {
        let bound = ESCAPE_FACTOR * initial.max(1.0);
        if !matches!(
            last.partial_cmp(&bound),
            Some(std::cmp::Ordering::Less | std::cmp::Ordering::Equal)
        ) {
            warnings.push(Warning {
                kind: "escape",
                message: format!(
                    "the configuration grew from {initial:.3e} to {last:.3e} (more than {} \
                     times): the motion escaped",
                    ESCAPE_FACTOR
                ),
            });
        }
    }
    if measured.retries > 0 {
        for warning in &mut warnings {
            warning.message.push_str(&format!(
                "; {} failed steps were retried with h/2: recovery kept the run going, it did \
                 not make it accurate",
                measured.retries
            ));
        }
    }
    warnings
}

/// A warning for each diagnostic `(name, value)` that was measured but is not a finite
/// number.
pub fn non_finite(diagnostics: &[(&str, Option<f64>)]) -> Vec<Warning> {
    diagnostics
        .iter()
        .filter(|(_, value)| value.is_some_and(|x| !x.is_finite()))
        .map(|(name, value)| Warning {
            kind: "non_finite",
            message: format!(
                "{name} is {} (JSON null): the diagnostic overflowed and means nothing",
                value.unwrap_or(f64::NAN)
            ),
        })
        .collect()
}

/// What the check of a pseudospectral run looks at: each a deviation and the scale it is
/// measured against.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FieldMeasured {
    /// Largest relative deviation of the discrete norm (mass), |N − N₀|/N₀.
    pub norm_error_relative: f64,
    /// |H − H₀| and the energy's scale |H₀|.
    pub energy: (f64, f64),
    /// Largest |ψ − ψ_exact| and the field's scale max|ψ₀|.
    pub solution: (f64, f64),
}

/// The checks a pseudospectral run fails: a norm, energy or solution error above
/// [`ENERGY_TOLERANCE`] of its scale (a NaN never passes).
pub fn check_field(measured: &FieldMeasured) -> Vec<Warning> {
    let within = |error: f64, scale: f64| error <= ENERGY_TOLERANCE * scale;
    let mut warnings = Vec::new();
    if !within(measured.norm_error_relative, 1.0) {
        warnings.push(Warning {
            kind: "norm",
            message: format!(
                "the norm changed by {:.3e} of its initial value (more than {} %): the \
                 scheme lost unitarity, and the result is not to be trusted",
                measured.norm_error_relative,
                100.0 * ENERGY_TOLERANCE
            ),
        });
    }
    let (error, scale) = measured.energy;
    if !within(error, scale) {
        warnings.push(Warning {
            kind: "energy",
            message: format!(
                "the energy error {error:.3e} is more than {} % of the energy's scale \
                 {scale:.3e}: the step does not resolve the motion",
                100.0 * ENERGY_TOLERANCE
            ),
        });
    }
    let (error, scale) = measured.solution;
    if !within(error, scale) {
        warnings.push(Warning {
            kind: "solution",
            message: format!(
                "the error against the exact solution, {error:.3e}, is more than {} % of the \
                 field's size {scale:.3e}: the grid or the step does not resolve the field, \
                 and the result is not to be trusted",
                100.0 * ENERGY_TOLERANCE
            ),
        });
    }
    warnings
}

#[cfg(test)]
mod tests {
    use super::*;

    fn measured(error: f64, scale: f64) -> Measured {
        Measured {
            conserves_energy: true,
            energy_initial: -0.5,
            energy_final: -0.5 + error,
            energy_error_max: Some(error),
            energy_scale: scale,
            extent: Some((1.0, 2.0)),
            retries: 0,
        }
    }

    #[test]
    fn an_energy_error_above_one_percent_of_the_scale_is_a_warning() {
        assert!(check(&measured(4.9e-3, 0.5)).is_empty());
        let warnings = check(&measured(5.1e-3, 0.5));
        assert_eq!(warnings.len(), 1);
        assert_eq!(warnings[0].kind, "energy");
        assert!(
            warnings[0].message.contains("1.020 %"),
            "{}",
            warnings[0].message
        );
        assert!(
            warnings[0]
                .message
                .starts_with("the largest energy error over the run, 5.100e-3, is"),
            "{}",
            warnings[0].message
        );
        // Not observed at every step: the final point's error, and the message says so.
        let unobserved = Measured {
            energy_error_max: None,
            energy_final: -0.5 - 6e-3,
            ..measured(0.0, 0.5)
        };
        let warnings = check(&unobserved);
        assert!(
            warnings[0]
                .message
                .starts_with("the final energy error (the energy was not observed at every step), 6.000e-3, is 1.200 %"),
            "{}",
            warnings[0].message
        );
        // NaN is never healthy; a model that does not conserve energy is not checked.
        assert_eq!(check(&measured(f64::NAN, 0.5)).len(), 1);
        let forced = Measured {
            conserves_energy: false,
            ..measured(1.0, 0.5)
        };
        assert!(check(&forced).is_empty());
    }

    #[test]
    fn non_finite_diagnostics_are_named() {
        let warnings = non_finite(&[
            ("energy_error_max", Some(1e-3)),
            ("momentum_error_max", Some(f64::NAN)),
            ("solution_error_max", None),
            ("invariant_error_max", Some(f64::INFINITY)),
        ]);
        let messages: Vec<&str> = warnings.iter().map(|w| w.message.as_str()).collect();
        assert_eq!(messages.len(), 2);
        assert!(messages[0].starts_with("momentum_error_max is NaN"));
        assert!(messages[1].starts_with("invariant_error_max is inf"));
    }

    #[test]
    fn a_field_run_is_checked_for_norm_energy_and_solution() {
        let healthy = FieldMeasured {
            norm_error_relative: 1e-14,
            energy: (1e-10, 2.0),
            solution: (1e-8, 1.0),
        };
        assert!(check_field(&healthy).is_empty());
        let lost = FieldMeasured {
            norm_error_relative: f64::NAN,
            energy: (0.5, 2.0),
            solution: (0.9, 1.0),
        };
        let kinds: Vec<&str> = check_field(&lost).iter().map(|w| w.kind).collect();
        assert_eq!(kinds, ["norm", "energy", "solution"]);
    }

    #[test]
    fn an_escaped_configuration_is_a_warning_and_recovery_is_named() {
        let escaped = Measured {
            extent: Some((0.5, 150.0)),
            retries: 3,
            ..measured(1.0, 0.5)
        };
        let warnings = check(&escaped);
        let kinds: Vec<&str> = warnings.iter().map(|w| w.kind).collect();
        assert_eq!(kinds, ["energy", "escape"]);
        assert!(
            warnings
                .iter()
                .all(|w| w.message.contains("3 failed steps were retried"))
        );
        let bounded = Measured {
            extent: Some((0.5, 99.0)),
            ..measured(0.0, 0.5)
        };
        assert!(check(&bounded).is_empty());
    }
}
