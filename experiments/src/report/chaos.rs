//! The chaos indicators of a run in its summary (`--indicators`): MEGNO, the maximal
//! Lyapunov exponent, the Lyapunov spectrum, SALI and GALI_N at the end of the run, from the method's
//! exact tangent maps ([`svi::analysis::chaos`]).

use serde::Serialize;

use crate::report::csv::{Float, vector};

/// The indicators asked for, at the end of the run.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct IndicatorSummary {
    /// MEGNO's time average ⟨Y⟩ (2 for quasi-periodic orbits, ≈ λt/2 for chaotic ones).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub megno: Option<f64>,
    /// The maximal Lyapunov exponent (one deviation vector).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lyapunov_max: Option<f64>,
    /// All 2N Lyapunov exponents, largest first.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lyapunov: Option<Vec<f64>>,
    /// The smaller alignment index SALI (→ 0 exponentially on chaotic orbits).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sali: Option<f64>,
    /// GALI_N, the volume spanned by N unit deviation vectors (N the coordinates): about
    /// constant on regular orbits (of an N-torus), → 0 exponentially on chaotic ones.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gali: Option<f64>,
}

impl IndicatorSummary {
    /// The summary's lines.
    pub fn rows(&self) -> Vec<(&'static str, String)> {
        let mut rows = Vec::new();
        if let Some(megno) = self.megno {
            rows.push(("MEGNO", Float(megno).to_string()));
        }
        if let Some(lambda) = self.lyapunov_max {
            rows.push(("Lyapunov max", Float(lambda).to_string()));
        }
        if let Some(spectrum) = &self.lyapunov {
            let sum: f64 = spectrum.iter().sum();
            rows.push((
                "Lyapunov",
                format!("{} (sum {:.1e})", vector(spectrum), sum),
            ));
        }
        if let Some(sali) = self.sali {
            rows.push(("SALI", format!("{sali:.3e}")));
        }
        if let Some(gali) = self.gali {
            rows.push(("GALI_N", format!("{gali:.3e}")));
        }
        rows
    }
}
