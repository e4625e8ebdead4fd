//! The energy behaviour of a long run: the energy error sampled in windows, the line fitted
//! through the window means, and its verdict (drifts, bounded, round-off).

use serde::Serialize;
use svi::drift::{DriftFit, EnergyWindows, Window};

/// Windows of the drift fit.
pub(super) const WINDOWS: usize = 100;
/// Largest number of energy samples of a drift run.
pub(super) const SAMPLES: usize = 100_000;

/// Fewest steps of the long run (two per window of the drift fit).
pub const MIN_DRIFT_STEPS: usize = 2 * WINDOWS;

/// Energy behaviour of one long run.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Drift {
    /// Steps taken (accepted plus rejected for DOP853).
    pub steps: usize,
    /// Step (the scene's; `None` for DOP853 and step doubling).
    pub h: Option<f64>,
    /// Horizon of the run.
    pub horizon: f64,
    /// Fitted slope of the energy error (per unit time).
    pub slope: f64,
    /// Slope × horizon.
    pub drift: f64,
    /// Mean half-range of the energy error in the windows.
    pub amplitude: f64,
    /// Largest |E − E₀|.
    pub max_error: f64,
    /// max(|E₀|, 1), the scale of the round-off floor.
    pub energy_scale: f64,
    /// Wall time, in seconds.
    pub seconds: f64,
    /// The windows.
    #[serde(skip)]
    pub windows: Vec<Window>,
}

/// Energy errors below this many ulps of max(|E₀|, 1) are round-off.
const ROUND_OFF: f64 = 1e3 * f64::EPSILON;

impl Drift {
    /// Whether the drift over the run exceeds both the oscillation amplitude and the
    /// round-off floor 10³·ε·max(|E₀|, 1).
    pub fn drifts(&self) -> bool {
        self.drift.abs() > self.amplitude && self.drift.abs() > ROUND_OFF * self.energy_scale
    }

    /// `drifts`, `bounded`, or `round-off` (every error below the round-off floor).
    pub fn verdict(&self) -> &'static str {
        if self.max_error <= ROUND_OFF * self.energy_scale {
            "round-off"
        } else if self.drifts() {
            "drifts"
        } else {
            "bounded"
        }
    }
}

/// Fit the drift of collected windows.
pub(super) fn drift(
    windows: &EnergyWindows,
    steps: usize,
    h: Option<f64>,
    seconds: f64,
) -> Result<Drift, String> {
    let all = windows.all();
    let fit: DriftFit = DriftFit::from_windows(&all)
        .ok_or_else(|| "no fit (too few or non-finite samples)".to_string())?;
    Ok(Drift {
        steps,
        h,
        horizon: fit.horizon,
        slope: fit.slope,
        drift: fit.drift,
        amplitude: fit.amplitude,
        max_error: fit.max_error,
        energy_scale: windows.initial.map_or(1.0, |e| e.abs().max(1.0)),
        seconds,
        windows: all,
    })
}
