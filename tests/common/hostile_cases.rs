//! The case budget of the property tests, shared by the library's and the CLI's hostile-input
//! tests.

use proptest::test_runner::Config as ProptestConfig;

/// `base` cases, times `SVI_HOSTILE_CASES` if set (for a longer search).
pub fn cases(base: u32) -> ProptestConfig {
    let factor = std::env::var("SVI_HOSTILE_CASES")
        .ok()
        .and_then(|v| v.parse::<u32>().ok())
        .unwrap_or(1)
        .max(1);
    ProptestConfig {
        cases: base.saturating_mul(factor),
        failure_persistence: None,
        // A failing case is reported after at most this many shrinking steps (each may be
        // a run), not after minutes of shrinking.
        max_shrink_iters: 2000,
        ..ProptestConfig::default()
    }
}
