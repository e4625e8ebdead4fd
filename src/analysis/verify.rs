//! Convergence-order verification, for `svi`'s own tests and for users' models.
//!
//! [`observed_order`] fits the slope of log(error) against log(h) by least squares over a
//! step-size ladder, using only the points above the round-off plateau, so a method's
//! declared order ([`crate::MethodInfo::order`]) can be checked on any model.

use crate::error::Error;

/// Least-squares slope of log(error) against log(h).
///
/// Points with error below `floor` (the round-off plateau) or non-positive are dropped;
/// at least two points must remain.
pub fn observed_order(steps: &[f64], errors: &[f64], floor: f64) -> Result<f64, Error> {
    if steps.len() != errors.len() {
        return Err(Error::invalid(
            "errors",
            format!("{} errors for {} step sizes", errors.len(), steps.len()),
        ));
    }
    let points: Vec<(f64, f64)> = steps
        .iter()
        .zip(errors)
        .filter(|&(&h, &e)| h > 0.0 && e > floor && e.is_finite() && h.is_finite())
        .map(|(h, e)| (h.ln(), e.ln()))
        .collect();
    if points.len() < 2 {
        return Err(Error::invalid(
            "errors",
            format!(
                "only {} points above the round-off floor {floor:e}",
                points.len()
            ),
        ));
    }
    let n = points.len() as f64;
    let mean_x = points.iter().map(|p| p.0).sum::<f64>() / n;
    let mean_y = points.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = points.iter().map(|p| (p.0 - mean_x).powi(2)).sum();
    let sxy: f64 = points.iter().map(|p| (p.0 - mean_x) * (p.1 - mean_y)).sum();
    if sxx == 0.0 {
        return Err(Error::invalid("steps", "all step sizes are equal"));
    }
    Ok(sxy / sxx)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recovers_a_known_power_law_and_drops_the_plateau() {
        let steps = [0.1, 0.05, 0.025, 0.0125, 0.00625];
        let errors: Vec<f64> = steps.iter().map(|h: &f64| 3.0 * h.powi(4)).collect();
        let mut with_plateau = errors.clone();
        with_plateau[4] = 1e-16;
        assert!((observed_order(&steps, &errors, 0.0).unwrap() - 4.0).abs() < 1e-12);
        assert!((observed_order(&steps, &with_plateau, 1e-14).unwrap() - 4.0).abs() < 1e-12);
        assert!(observed_order(&steps[..1], &errors[..1], 0.0).is_err());
    }
}
