//! The progress bar of long runs.

use std::ops::ControlFlow;

use indicatif::{ProgressBar, ProgressStyle};
use svi::observer::Observer;

/// Runs with at least this many steps show a progress bar (on a terminal).
pub const PROGRESS_MIN_STEPS: usize = 10_000;

/// Runs of at least this many coordinate-steps (steps × coordinates) show a progress bar too:
/// 100 steps of a chain of 10⁵ particles take seconds. A model of at most 3 coordinates
/// reaches it only beyond [`PROGRESS_MIN_STEPS`] steps.
pub const PROGRESS_MIN_WORK: usize = 1_000_000;

/// A progress bar on stderr, updated about every 1 % of the steps.
#[derive(Debug)]
pub struct Progress {
    bar: ProgressBar,
    stride: usize,
}

impl Progress {
    /// A progress bar for `steps` steps.
    pub fn new(steps: usize) -> Self {
        let bar = ProgressBar::new(steps as u64);
        if let Ok(style) =
            ProgressStyle::with_template("{bar:40} {pos}/{len} steps, {elapsed} (eta {eta})")
        {
            bar.set_style(style);
        }
        Progress {
            bar,
            stride: (steps / 100).max(1),
        }
    }

    /// A progress bar for a run of a model with `coordinates` coordinates from `t0` to
    /// `t_end` with step `h`, or `None` if the run has fewer than [`PROGRESS_MIN_STEPS`]
    /// steps and fewer than [`PROGRESS_MIN_WORK`] coordinate-steps (or invalid inputs, which
    /// the run rejects).
    pub fn for_run(t0: f64, h: f64, t_end: f64, coordinates: usize) -> Option<Self> {
        let steps = svi::step_count(t_end - t0, h).ok()?;
        let long =
            steps >= PROGRESS_MIN_STEPS || steps.saturating_mul(coordinates) >= PROGRESS_MIN_WORK;
        long.then(|| Progress::new(steps))
    }

    /// A progress bar over `levels` time levels of a field of `nodes` nodes, or `None` if
    /// the run is short in both senses of [`Progress::for_run`].
    pub fn for_levels(levels: usize, nodes: usize) -> Option<Self> {
        let long =
            levels >= PROGRESS_MIN_STEPS || levels.saturating_mul(nodes) >= PROGRESS_MIN_WORK;
        long.then(|| Progress::new(levels))
    }

    /// Show `step` done (about every 1 % of the steps).
    pub fn advance(&self, step: usize) {
        if step > 0 && step.is_multiple_of(self.stride) {
            self.bar.set_position(step as u64);
        }
    }

    /// Remove the bar.
    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

impl<L: ?Sized, P> Observer<L, P> for Progress {
    fn wants(&self, step: usize) -> bool {
        step > 0 && step.is_multiple_of(self.stride)
    }

    fn observe(&mut self, _: &L, step: usize, _: &P) -> ControlFlow<()> {
        self.bar.set_position(step as u64);
        ControlFlow::Continue(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use svi::observer::Observer;

    #[test]
    fn progress_is_only_for_long_runs() {
        assert!(Progress::for_run(0.0, 0.2, 2000.0, 2).is_some());
        assert!(Progress::for_run(0.0, 1.0, 100.0, 2).is_none());
        assert!(Progress::for_run(0.0, 0.0, 100.0, 2).is_none());
        assert!(Progress::for_run(0.0, -1.0, 100.0, 2).is_none());
        // 100 steps of 10⁵ coordinates, not of 10³.
        assert!(Progress::for_run(0.0, 0.1, 10.0, 100_000).is_some());
        assert!(Progress::for_run(0.0, 0.1, 10.0, 1000).is_none());
        let progress = Progress::new(10_000);
        assert_eq!(progress.stride, 100);
        let wants = |step| Observer::<(), ()>::wants(&progress, step);
        assert!(!wants(0));
        assert!(!wants(150));
        assert!(wants(200));
    }
}
