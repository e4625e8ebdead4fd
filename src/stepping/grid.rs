//! The fixed time grid of a run: how many steps cover a span, and where step k starts and
//! ends. Times are t_k = t_0 + k·h, never accumulated with `t += h`; the last step is
//! shortened to land on the horizon.

use crate::error::Error;

/// Number of steps [`crate::Integrator::run`] takes to cover `span` with steps of size at most `h`:
/// a span within round-off of a whole number of steps gets no extra sliver step, otherwise
/// the last step is shortened.
pub fn step_count(span: f64, h: f64) -> Result<usize, Error> {
    let ratio = span / h;
    if !ratio.is_finite() || ratio > 1e12 {
        return Err(Error::invalid(
            "h",
            format!("step {h} is too small for the span {span} (more than 10^12 steps)"),
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
    }
}
