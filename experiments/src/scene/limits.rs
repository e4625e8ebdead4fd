//! The limits of what a user may ask `svi` for: every count and time budget set on the
//! command line has a cap, stated once here (and in the option's `--help` and the guide's
//! chapter "Limits", `docs/guide/src/limits.md`), so that no input makes a command read, run
//! or allocate without bound. A value out of range is bad input (exit status 2) whose message
//! names the option.

use std::path::Path;

use crate::report::csv::Float;
use crate::report::output::file_kind;
use crate::scene::error::SceneError;

/// Largest scene file read (1 MiB): a scene is a short TOML file.
pub const MAX_SCENE_BYTES: u64 = 1 << 20;

/// Most grid points of `svi stability --samples` (10⁵: a 12 MB CSV, 2 s for svi:9/18).
pub const MAX_SAMPLES: usize = 100_000;

/// Most timing batches per point of `svi bench --batches`.
pub const MAX_BATCHES: usize = 100;

/// Longest minimum batch duration of `svi bench --min-batch`, in seconds.
pub const MAX_BATCH_SECONDS: f64 = 60.0;

/// Longest single-run limit of `svi bench --max-run`, in seconds.
pub const MAX_RUN_SECONDS: f64 = 3600.0;

/// Most steps of one run of `svi bench` (each `--steps` entry, and where a sweep stops).
pub const MAX_STEPS: usize = 100_000_000;

/// Most steps of the long run of `svi stress --steps` (10 times the default; DOP853 keeps
/// every step it takes, about 40 bytes each, up to 15 per svi step on the stiff spring).
pub const MAX_DRIFT_STEPS: usize = 10_000_000;

/// Most bisections of `svi stress --bisections` (after 50 the two ends of a boundary are
/// adjacent floating-point numbers).
pub const MAX_BISECTIONS: usize = 50;

/// Smallest tolerance of the adaptive peers (`dop853`, `dopri5`; `svi bench --tolerances`,
/// `svi stress --tolerance`): 1e-20 (`radau5` needs more, see `svi bench --help`). Their
/// error stops improving near 1e-16 (round-off), while their step count, and the step points
/// `ode_solvers` keeps, grow as tol^(−1/order) without bound: at 1e-300 some 10³⁵ times as
/// many steps.
pub const MIN_PEER_TOLERANCE: f64 = 1e-20;

/// The memory a run may ask for: two thirds of the machine's physical memory (16 GB on a
/// machine of 24 GB), or 16 GB where the machine does not tell.
pub fn memory_budget() -> f64 {
    #[cfg(unix)]
    {
        // SAFETY: sysconf reads a system constant; it has no memory effects.
        let (pages, size) = unsafe {
            (
                libc::sysconf(libc::_SC_PHYS_PAGES),
                libc::sysconf(libc::_SC_PAGESIZE),
            )
        };
        if pages > 0 && size > 0 {
            return 2.0 / 3.0 * pages as f64 * size as f64;
        }
    }
    16e9
}

/// The estimated peak memory of a run on a chain of `n` particles, in bytes: by `method`
/// (`points` its CGL points), its structure (a constant mass lets `svi` take the fixed point)
/// and the states kept at `outputs` output times (q, v and p of n components each, in the
/// summary and its JSON text). Per particle, measured at n = 2·10⁵ and 10⁶ (peak RSS,
/// `/usr/bin/time`, 2026-11-27) and raised by a quarter: the explicit methods 250 bytes;
/// SVI's fixed point 210 + 63·P bytes; sparse Newton (`svi-newton`, or `svi` with a
/// velocity-dependent mass) 1040 + 125·s² bytes for s = P − 1 stage vectors (its Jacobian
/// couples neighbours' stages, and its LU factors fill in); 28 bytes per number kept at an
/// output time.
pub fn chain_memory(
    n: usize,
    method: &str,
    points: Option<usize>,
    constant_mass: bool,
    outputs: usize,
) -> f64 {
    let points = points.unwrap_or(6) as f64;
    let per_particle = match method {
        "svi-newton" => 1040.0 + 125.0 * (points - 1.0).powi(2),
        "svi" if !constant_mass => 1040.0 + 125.0 * (points - 1.0).powi(2),
        "svi" => 210.0 + 63.0 * points,
        _ => 250.0,
    };
    let n = n as f64;
    16e6 + 1.25 * per_particle * n + 28.0 * 3.0 * n * outputs as f64
}

/// The estimated peak memory of a pseudospectral run on `modes` Fourier modes whose time
/// scheme has `stages` stages (the Galerkin degree; 1 for Strang), in bytes: per mode
/// 100 + 100·s + 13·s² bytes (the stage fields, their transforms and the Gauss tableau's
/// products), measured at 2¹⁸ modes for s = 1, 3, 4, 8, 16 (peak RSS, 2026-11-27) and raised
/// by a quarter.
pub fn spectral_memory(modes: usize, stages: usize) -> f64 {
    let s = stages as f64;
    16e6 + 1.25 * (100.0 + 100.0 * s + 13.0 * s * s) * modes as f64
}

/// Refuse a run whose estimated memory `estimate` (bytes) is above [`memory_budget`], naming
/// `option` and the estimate.
pub fn check_memory(option: &'static str, estimate: f64, what: &str) -> Result<(), SceneError> {
    let budget = memory_budget();
    if estimate <= budget {
        return Ok(());
    }
    Err(SceneError::InvalidOption {
        option,
        reason: format!(
            "{what} needs about {:.1} GB of memory, more than the {:.1} GB a run may take (two \
             thirds of this machine's memory)",
            estimate / 1e9,
            budget / 1e9
        ),
    })
}

/// A tolerance of an adaptive peer for `option`: finite and at least
/// [`MIN_PEER_TOLERANCE`], else an error naming the option.
pub fn peer_tolerance(option: &'static str, value: f64) -> Result<f64, SceneError> {
    if value.is_finite() && value >= MIN_PEER_TOLERANCE {
        Ok(value)
    } else {
        Err(SceneError::InvalidOption {
            option,
            reason: format!(
                "{}; need a finite tolerance of at least {} (below it the step count grows \
                 without gaining accuracy)",
                Float(value),
                Float(MIN_PEER_TOLERANCE)
            ),
        })
    }
}

/// A count set by the user for `option`: `low` to `cap` `what`, else an error naming the
/// option, the value and the range.
pub fn count(
    option: &'static str,
    value: usize,
    low: usize,
    cap: usize,
    what: &str,
) -> Result<usize, SceneError> {
    if (low..=cap).contains(&value) {
        Ok(value)
    } else {
        Err(SceneError::InvalidOption {
            option,
            reason: format!("{value} {what}; need {low} to {cap}"),
        })
    }
}

/// A time budget in seconds for `option`: finite, positive (or zero where `zero` means
/// something) and at most `cap`, else an error naming the option.
pub fn seconds(option: &'static str, value: f64, zero: bool, cap: f64) -> Result<f64, SceneError> {
    let low_ok = if zero { value >= 0.0 } else { value > 0.0 };
    if value.is_finite() && low_ok && value <= cap {
        Ok(value)
    } else {
        let low = if zero { "of 0 s or more" } else { "above 0 s" };
        Err(SceneError::InvalidOption {
            option,
            reason: format!(
                "{} s; need a finite duration {low}, at most {} s",
                Float(value),
                Float(cap)
            ),
        })
    }
}

/// A finite positive number for `option`, else an error naming the option.
pub fn positive(option: &'static str, value: f64) -> Result<f64, SceneError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(SceneError::InvalidOption {
            option,
            reason: format!("{}; need a finite positive number", Float(value)),
        })
    }
}

/// The text of the scene file at `path`, read only if it is a regular file of at most
/// [`MAX_SCENE_BYTES`]: a directory, a FIFO, a device or a huge file is an error naming it
/// ([`SceneError::NotASceneFile`]), never an endless read.
pub fn read_scene_file(path: &Path) -> Result<String, SceneError> {
    use std::io::Read;
    let not_a_scene = |reason: String| SceneError::NotASceneFile {
        path: path.into(),
        reason,
    };
    let read_error = |source: std::io::Error| SceneError::Read {
        path: path.into(),
        source,
    };
    // Ask before opening: opening a FIFO blocks until a writer comes.
    let metadata = std::fs::metadata(path).map_err(read_error)?;
    if !metadata.is_file() {
        return Err(not_a_scene(format!("it is {}", file_kind(&metadata))));
    }
    let too_large = || {
        not_a_scene(format!(
            "it is larger than {MAX_SCENE_BYTES} bytes (1 MiB), the limit for a scene"
        ))
    };
    if metadata.len() > MAX_SCENE_BYTES {
        return Err(too_large());
    }
    // A file may grow, or report no size (/proc): read at most one byte past the limit.
    let file = std::fs::File::open(path).map_err(read_error)?;
    let mut bytes = Vec::new();
    file.take(MAX_SCENE_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(read_error)?;
    if bytes.len() as u64 > MAX_SCENE_BYTES {
        return Err(too_large());
    }
    String::from_utf8(bytes).map_err(|error| {
        read_error(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!("not UTF-8 text ({error})"),
        ))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_and_budgets_name_the_option_and_the_range() {
        assert_eq!(count("--batches", 5, 1, MAX_BATCHES, "batches").unwrap(), 5);
        let error = count("--batches", 0, 1, MAX_BATCHES, "batches").unwrap_err();
        assert_eq!(
            error.to_string(),
            "invalid --batches: 0 batches; need 1 to 100"
        );
        assert!(error.is_bad_input());
        assert_eq!(seconds("--min-batch", 0.0, true, 60.0).unwrap(), 0.0);
        for bad in [f64::NAN, f64::INFINITY, -1.0, 61.0, 1e300] {
            let error = seconds("--min-batch", bad, true, 60.0).unwrap_err();
            assert!(
                error.to_string().starts_with("invalid --min-batch: "),
                "{error}"
            );
        }
        assert!(seconds("--max-run", 0.0, false, 3600.0).is_err());
        let error = positive("--target", -1e-300).unwrap_err();
        assert_eq!(
            error.to_string(),
            "invalid --target: -1e-300; need a finite positive number"
        );
    }
}
