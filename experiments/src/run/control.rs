//! How a caller watches and stops a run: a progress bar, and a flag asked between steps.
//!
//! The flag is read every [`STOP_STRIDE`] steps inside [`Observer::wants`], so a run that is
//! not stopped completes no extra point and computes exactly what an unwatched run computes
//! (an observed point refreshes the next Newton guess). The Python package sets the flag
//! when Ctrl-C reaches the interpreter and raises `KeyboardInterrupt`.

use std::ops::ControlFlow;
use std::sync::atomic::{AtomicBool, Ordering};

use svi::observer::Observer;

/// A stopped run ends at most this many steps after the flag is set.
pub const STOP_STRIDE: usize = 64;

/// How a run is watched.
#[derive(Debug, Clone, Copy, Default)]
pub struct Control<'a> {
    /// Draw a progress bar on stderr for a fixed-grid run of at least
    /// [`crate::report::progress::PROGRESS_MIN_STEPS`] steps (or as much work).
    pub progress: bool,
    /// Stop the run when this flag is set: it then ends with [`crate::SceneError::Interrupted`]
    /// within [`STOP_STRIDE`] steps.
    pub stop: Option<&'a AtomicBool>,
}

impl Control<'_> {
    /// No progress bar and no stop flag.
    pub const QUIET: Control<'static> = Control {
        progress: false,
        stop: None,
    };

    /// Whether the stop flag is set.
    pub fn stopped(&self) -> bool {
        self.stop.is_some_and(|stop| stop.load(Ordering::Relaxed))
    }
}

/// The observer of a stop flag: it wants a step only to stop the run there.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Stop<'a>(pub &'a AtomicBool);

impl<L: ?Sized, P> Observer<L, P> for Stop<'_> {
    fn wants(&self, step: usize) -> bool {
        step.is_multiple_of(STOP_STRIDE) && self.0.load(Ordering::Relaxed)
    }
    fn observe(&mut self, _: &L, _: usize, _: &P) -> ControlFlow<()> {
        ControlFlow::Break(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stop_flag_is_wanted_only_once_set_and_on_the_stride() {
        let flag = AtomicBool::new(false);
        let mut stop = Stop(&flag);
        let wants = |stop: &Stop, step| Observer::<(), ()>::wants(stop, step);
        assert!(!wants(&stop, 0));
        assert!(!wants(&stop, STOP_STRIDE));
        flag.store(true, Ordering::Relaxed);
        assert!(wants(&stop, STOP_STRIDE));
        assert!(!wants(&stop, STOP_STRIDE + 1));
        assert!(Observer::<(), ()>::observe(&mut stop, &(), 0, &()).is_break());
        assert!(
            Control {
                progress: false,
                stop: Some(&flag)
            }
            .stopped()
        );
        assert!(!Control::QUIET.stopped());
    }
}
