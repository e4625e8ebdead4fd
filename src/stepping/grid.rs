//! The fixed time grid of a run: how many steps cover a span, and where step k starts and
//! ends. Times are t_k = t_0 + k·h, never accumulated with `t += h`; the last step is
//! shortened to land on the horizon.

use crate::error::{Error, require_finite, require_positive};

/// Most steps of one fixed-grid run: 10⁹ (about 20 minutes of SVI on Kepler, 12 days at
/// 10¹²); longer runs are split by the caller.
pub const MAX_STEPS: usize = 1_000_000_000;

/// Number of steps [`crate::Integrator::run`] takes to cover `span` with steps of size at most `h`:
/// a span within round-off of a whole number of steps gets no extra sliver step, otherwise
/// the last step is shortened.
pub fn step_count(span: f64, h: f64) -> Result<usize, Error> {
    let ratio = span / h;
    if !ratio.is_finite() || ratio > MAX_STEPS as f64 {
        return Err(Error::invalid(
            "h",
            format!(
                "step {h:?} is too small for the span {span:?}: more than {MAX_STEPS:e} steps \
                 (split the run, or take a larger step)"
            ),
        ));
    }
    let nearest = ratio.round();
    let count = if (ratio - nearest).abs() <= 1e-9 * ratio.max(1.0) {
        nearest
    } else {
        ratio.ceil()
    };
    Ok((count as usize).max(1))
}

/// Smallest step, in units of the spacing of floating-point times near the span, that a
/// run accepts.
pub const RESOLUTION: f64 = 1e3;

/// The finest step whose times can be told apart near [t0, t_end]: [`RESOLUTION`] spacings of
/// the floating-point numbers there (with t0 = 10¹⁶ they are 2 apart, and t0 + 0.4 is t0).
pub fn resolution(t0: f64, t_end: f64) -> f64 {
    RESOLUTION * f64::EPSILON * t0.abs().max(t_end.abs())
}

/// Check a span: finite ends, t_end after t0, and long enough for at least one resolvable
/// step ([`resolution`]).
pub fn check_span(t0: f64, t_end: f64) -> Result<(), Error> {
    require_finite("t0", t0)?;
    require_finite("t_end", t_end)?;
    if t_end <= t0 {
        return Err(Error::invalid(
            "t_end",
            format!("the horizon {t_end:?} is not after the start {t0:?}"),
        ));
    }
    let finest = resolution(t0, t_end);
    if t_end - t0 < finest {
        return Err(Error::invalid(
            "t_end",
            format!(
                "the span from {t0:e} to {t_end:e} is shorter than the finest step {finest:e} \
                 whose times floating point can tell apart there: start the time at 0"
            ),
        ));
    }
    Ok(())
}

/// The number of steps of the fixed grid of step `h` over [t0, t_end] ([`step_count`]), after
/// checking the span ([`check_span`]) and that `h` is positive and resolvable
/// ([`resolution`]).
pub fn grid_steps(t0: f64, t_end: f64, h: f64) -> Result<usize, Error> {
    check_span(t0, t_end)?;
    require_positive("h", h)?;
    let finest = resolution(t0, t_end);
    if h < finest {
        // Starting the time at 0 helps only where the span itself is resolvable from 0.
        let advice = if h >= resolution(0.0, t_end - t0) {
            "start the time at 0 or take a larger step"
        } else {
            "take a larger step or a shorter span"
        };
        return Err(Error::invalid(
            "h",
            format!(
                "step {h:e} is below the finest step {finest:e} whose times floating point \
                 can tell apart near {:e}: {advice}",
                t0.abs().max(t_end.abs())
            ),
        ));
    }
    step_count(t_end - t0, h)
}

/// Step `k` of the fixed grid t_j = t0 + j·h covering [t0, t_end] in `steps` steps (see
/// [`step_count`]): (start time, step size, end time). Times are never accumulated, and the
/// last step is shortened to end exactly at `t_end`.
pub(crate) fn grid_step(t0: f64, t_end: f64, h: f64, steps: usize, k: usize) -> (f64, f64, f64) {
    let t = t0 + k as f64 * h;
    if k + 1 == steps {
        (t, t_end - t, t_end)
    } else {
        (t, h, t0 + (k + 1) as f64 * h)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn step_count_lands_on_the_horizon() {
        assert_eq!(step_count(100.0, 1.0).unwrap(), 100);
        assert_eq!(step_count(2000.0, 0.2).unwrap(), 10000);
        assert_eq!(step_count(1.0, 0.3).unwrap(), 4);
        assert_eq!(step_count(0.1, 1.0).unwrap(), 1);
        assert!(step_count(1.0, 1e-300).is_err());
        assert_eq!(step_count(1e9, 1.0).unwrap(), MAX_STEPS);
        assert!(step_count(1e9 + 1.0, 1.0).is_err());
    }

    #[test]
    fn a_step_below_the_resolution_of_the_times_is_an_error() {
        // t0 = 1e16: neighbouring doubles are 2 apart, so steps of 0.4 would integrate 1.6
        // of 2 time units on repeated time stamps.
        let name = |result: Result<usize, Error>| match result {
            Err(Error::InvalidParameter { name, .. }) => name,
            other => panic!("expected a typed error, got {other:?}"),
        };
        assert_eq!(name(grid_steps(1e16, 1e16 + 2.0, 0.4)), "t_end");
        assert_eq!(name(grid_steps(1e16, 1e16 + 2e5, 0.4)), "h");
        // The advice: starting at 0 where that resolves the step, else a shorter span (from
        // 0 to 1e308, starting at 0 is no advice).
        let advice = |result: Result<usize, Error>| result.unwrap_err().to_string();
        assert!(advice(grid_steps(1e16, 1e16 + 2e5, 0.4)).contains("start the time at 0"));
        let far = advice(grid_steps(0.0, 1e308, 0.2));
        assert!(
            far.contains("near 1e308: take a larger step or a shorter span"),
            "{far}"
        );
        assert!(grid_steps(1e16, 1e16 + 2e5, 1e4).is_ok());
        // Ordinary spans are unaffected: 2.2e-10 is the finest step at t ≈ 1e3.
        assert_eq!(grid_steps(0.0, 1e3, 1e-3).unwrap(), 1_000_000);
        assert!(grid_steps(0.0, 1e3, 1e-10).is_err());
        assert!(grid_steps(-5e-3, 5e-3, 1e-9).is_ok());
    }
}
