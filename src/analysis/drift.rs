//! Long-time energy behaviour: the energy error sampled in windows, and its drift fitted by
//! least squares.
//!
//! A symplectic method keeps the energy error E(t) − E(t₀) bounded and oscillating over
//! exponentially long times (backward error analysis); a non-symplectic one (collocation,
//! explicit Runge–Kutta) lets it drift, typically linearly in t. [`EnergyWindows`] collects
//! the error in windows of a fixed number of samples (mean, minimum, maximum per window) and
//! [`DriftFit`] fits a straight line through the window means, as GeometricIntegrators.jl's
//! long-time diagnostics do: the slope times the horizon is the drift, the mean half-range
//! of the windows is the oscillation amplitude, and a method drifts when the first clearly
//! exceeds the second.
//!
//! ```
//! use svi::drift::EnergyWindows;
//!
//! // A bounded oscillation: no drift.
//! let mut windows = EnergyWindows::new(100);
//! for k in 0..10_000 {
//!     let t = 0.1 * k as f64;
//!     windows.push(t, 1e-6 * t.sin());
//! }
//! let fit = windows.fit().unwrap();
//! assert!(fit.drift.abs() < fit.amplitude);
//! ```

use crate::dimension::Dimension;
use crate::method::PhasePoint;
use crate::model::Lagrangian;
use crate::model::derived::LagrangianExt;
use crate::stepping::observer::Observer;
use nalgebra::DefaultAllocator;
use nalgebra::allocator::Allocator;
use std::ops::ControlFlow;

/// Statistics of the energy error over one window of samples.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Window {
    /// Time of the first sample.
    pub t_start: f64,
    /// Time of the last sample.
    pub t_end: f64,
    /// Mean error over the window.
    pub mean: f64,
    /// Smallest error in the window.
    pub min: f64,
    /// Largest error in the window.
    pub max: f64,
    /// Number of samples.
    pub samples: usize,
}

impl Window {
    fn start(t: f64, error: f64) -> Self {
        Window {
            t_start: t,
            t_end: t,
            mean: error,
            min: error,
            max: error,
            samples: 1,
        }
    }

    fn add(&mut self, t: f64, error: f64) {
        self.t_end = t;
        self.samples += 1;
        self.mean += (error - self.mean) / self.samples as f64;
        self.min = self.min.min(error);
        self.max = self.max.max(error);
    }

    /// The window's midpoint in time.
    pub fn t_mid(&self) -> f64 {
        0.5 * (self.t_start + self.t_end)
    }

    /// Half the range of the error in the window, (max − min)/2.
    pub fn half_range(&self) -> f64 {
        0.5 * (self.max - self.min)
    }
}

/// The energy error E − E₀ collected in windows of `size` samples; an [`Observer`] (it
/// evaluates the energy at every point it is given: thin it with
/// [`crate::stepping::observer::Every`]), or fed directly with [`EnergyWindows::push`] for methods
/// outside `svi`.
#[derive(Debug, Clone, PartialEq)]
pub struct EnergyWindows {
    /// Samples per window (at least 1).
    pub size: usize,
    /// Energy of the first sample.
    pub initial: Option<f64>,
    /// Completed windows, in time order.
    pub windows: Vec<Window>,
    /// The window being filled.
    current: Option<Window>,
}

impl EnergyWindows {
    /// Windows of `size` samples (0 is taken as 1).
    pub fn new(size: usize) -> Self {
        EnergyWindows {
            size: size.max(1),
            initial: None,
            windows: Vec::new(),
            current: None,
        }
    }

    /// Add the energy at time `t`; the first energy pushed is the reference E₀.
    pub fn push(&mut self, t: f64, energy: f64) {
        let initial = *self.initial.get_or_insert(energy);
        self.push_error(t, energy - initial);
    }

    /// Add an energy error E(t) − E₀ directly.
    pub fn push_error(&mut self, t: f64, error: f64) {
        match &mut self.current {
            Some(window) => window.add(t, error),
            None => self.current = Some(Window::start(t, error)),
        }
        if self.current.is_some_and(|w| w.samples >= self.size) {
            self.windows.extend(self.current.take());
        }
    }

    /// The completed windows and the one being filled (if it has samples).
    pub fn all(&self) -> Vec<Window> {
        self.windows.iter().copied().chain(self.current).collect()
    }

    /// Fit the drift over all windows (see [`DriftFit::from_windows`]).
    pub fn fit(&self) -> Option<DriftFit> {
        DriftFit::from_windows(&self.all())
    }
}

impl<L: Lagrangian<N>, N: Dimension> Observer<L, PhasePoint<N>> for EnergyWindows
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    fn observe(&mut self, model: &L, _: usize, point: &PhasePoint<N>) -> ControlFlow<()> {
        let energy = model.phase_energy(point.t, &point.q, &point.v, &point.p);
        self.push(point.t, energy);
        ControlFlow::Continue(())
    }
}

/// A straight line fitted by least squares through the window means of the energy error.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DriftFit {
    /// Fitted slope d(E − E₀)/dt.
    pub slope: f64,
    /// Fitted error at t = 0.
    pub intercept: f64,
    /// Time from the first to the last sample.
    pub horizon: f64,
    /// Slope × horizon: the energy error the drift accumulates over the run.
    pub drift: f64,
    /// Mean over the windows of half the error's range in the window: the amplitude of the
    /// bounded oscillation.
    pub amplitude: f64,
    /// Largest |E − E₀| over all samples.
    pub max_error: f64,
    /// Number of windows fitted.
    pub windows: usize,
}

impl DriftFit {
    /// Fit `windows` (at least two, with finite statistics and distinct midpoints); `None`
    /// otherwise.
    pub fn from_windows(windows: &[Window]) -> Option<DriftFit> {
        let finite = windows.iter().all(|w| {
            w.mean.is_finite() && w.min.is_finite() && w.max.is_finite() && w.t_mid().is_finite()
        });
        if windows.len() < 2 || !finite {
            return None;
        }
        let count = windows.len() as f64;
        let x_mean = windows.iter().map(Window::t_mid).sum::<f64>() / count;
        let y_mean = windows.iter().map(|w| w.mean).sum::<f64>() / count;
        let (mut sxy, mut sxx) = (0.0, 0.0);
        for w in windows {
            let dx = w.t_mid() - x_mean;
            sxy += dx * (w.mean - y_mean);
            sxx += dx * dx;
        }
        if sxx <= 0.0 {
            return None;
        }
        let slope = sxy / sxx;
        let horizon = windows[windows.len() - 1].t_end - windows[0].t_start;
        Some(DriftFit {
            slope,
            intercept: y_mean - slope * x_mean,
            horizon,
            drift: slope * horizon,
            amplitude: windows.iter().map(Window::half_range).sum::<f64>() / count,
            max_error: windows
                .iter()
                .map(|w| w.max.abs().max(w.min.abs()))
                .fold(0.0, f64::max),
            windows: windows.len(),
        })
    }

    /// Whether the drift over the run exceeds the oscillation amplitude.
    pub fn drifts(&self) -> bool {
        self.drift.abs() > self.amplitude
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_line_plus_an_oscillation_is_fitted() {
        let mut windows = EnergyWindows::new(50);
        let mut largest: f64 = 0.0;
        for k in 0..5000 {
            let t = 0.01 * k as f64;
            let error = 3e-4 * t + 1e-3 * (7.0 * t).sin();
            largest = largest.max(error.abs());
            windows.push_error(t, error);
        }
        let fit = windows.fit().unwrap();
        assert_eq!(fit.windows, 100);
        assert!((fit.slope - 3e-4).abs() < 3e-6, "{fit:?}");
        assert!((fit.horizon - 49.99).abs() < 1e-12);
        // Half-range of a sine over windows of 0.49 time units (0.55 of a period): < 1e-3.
        assert!(
            fit.amplitude > 5e-4 && fit.amplitude <= 1e-3 + 1e-6,
            "{fit:?}"
        );
        assert_eq!(fit.max_error, largest);
        assert!(largest > 3e-4 * 49.0 && largest < 3e-4 * 49.99 + 1e-3);
        assert!(fit.drift > fit.amplitude && fit.drifts());
    }

    #[test]
    fn too_few_or_non_finite_windows_give_no_fit() {
        let mut windows = EnergyWindows::new(10);
        windows.push(0.0, 1.0);
        assert!(windows.fit().is_none());
        for k in 1..30 {
            windows.push(k as f64, if k == 15 { f64::NAN } else { 1.0 });
        }
        assert!(windows.fit().is_none());
        assert_eq!(windows.all().len(), 3);
    }

    #[test]
    fn the_first_energy_is_the_reference() {
        let mut windows = EnergyWindows::new(2);
        windows.push(0.0, 5.0);
        windows.push(1.0, 5.5);
        assert_eq!(windows.initial, Some(5.0));
        assert_eq!(windows.windows[0].max, 0.5);
        assert_eq!(windows.windows[0].min, 0.0);
    }
}
