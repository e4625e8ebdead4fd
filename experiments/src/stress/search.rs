//! The largest step meeting a criterion: a geometric ladder of steps from the scene's step
//! up (or down), refined by bisection between the last good and the first failing step.

use serde::Serialize;

/// Ladder factor per probe: 2^(1/4).
const LADDER: f64 = 1.189_207_115_002_721;
/// Largest number of ladder rungs in either direction (a factor 2^12).
const RUNGS: i32 = 48;

/// The largest step meeting a criterion, and what happens just beyond it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Limit {
    /// Largest step found that meets the criterion (`None`: not even the smallest probed).
    pub h: Option<f64>,
    /// Smallest step found that fails it (`None`: none up to the largest probed).
    pub beyond: Option<f64>,
    /// What happens at `beyond`.
    pub failure: String,
}

/// The largest step in `range` for which `good` holds, searched from `h_ref` (see the module
/// documentation); `good(h)` returns whether the step is good and, if not, why.
pub(super) fn search(
    h_ref: f64,
    range: (f64, f64),
    bisections: usize,
    mut good: impl FnMut(f64) -> (bool, String),
) -> Limit {
    let h_ref = h_ref.clamp(range.0, range.1);
    let mut best: Option<f64> = None;
    let mut beyond: Option<(f64, String)> = None;
    let (ok, why) = good(h_ref);
    if ok {
        best = Some(h_ref);
        for j in 1..=RUNGS {
            let h = h_ref * LADDER.powi(j);
            if h > range.1 {
                break;
            }
            match good(h) {
                (true, _) => best = Some(h),
                (false, why) => {
                    beyond = Some((h, why));
                    break;
                }
            }
        }
    } else {
        beyond = Some((h_ref, why));
        for j in 1..=RUNGS {
            let h = h_ref / LADDER.powi(j);
            if h < range.0 {
                break;
            }
            match good(h) {
                (true, _) => {
                    best = Some(h);
                    break;
                }
                (false, why) => beyond = Some((h, why)),
            }
        }
    }
    if let (Some(low), Some((high, _))) = (best, &beyond) {
        let mut high = *high;
        let mut low = low;
        for _ in 0..bisections {
            let middle = (low * high).sqrt();
            match good(middle) {
                (true, _) => low = middle,
                (false, why) => {
                    high = middle;
                    beyond = Some((middle, why));
                }
            }
        }
        best = Some(low);
    }
    Limit {
        h: best,
        beyond: beyond.as_ref().map(|(h, _)| *h),
        failure: beyond.map_or_else(
            || {
                format!(
                    "none up to h = {}",
                    best.map_or_else(String::new, |h| format!("{h:.3e}"))
                )
            },
            |(_, why)| why,
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn search_finds_a_threshold_from_either_side() {
        let good = |h: f64| (h < 2.0, format!("fails at {h}"));
        let up = search(0.5, (1e-6, 100.0), 8, good);
        let h = up.h.unwrap();
        let beyond = up.beyond.unwrap();
        assert!(h < 2.0 && beyond >= 2.0 && beyond / h < 1.002, "{up:?}");
        assert!(up.failure.starts_with("fails at"));
        let down = search(10.0, (1e-6, 100.0), 8, good);
        assert!(down.h.unwrap() < 2.0 && down.h.unwrap() > 1.99, "{down:?}");
        let never = search(1.0, (1e-6, 100.0), 3, |_| (true, String::new()));
        assert_eq!(never.beyond, None);
        assert!(never.failure.starts_with("none up to"));
        assert!(never.h.unwrap() <= 100.0 && never.h.unwrap() > 100.0 / LADDER);
    }
}
