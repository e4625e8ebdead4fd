//! The stress cases and the options of `svi stress`: its arguments as the command line
//! parses them, and every check of them before anything runs.

use crate::bench::method::{BenchMethod, parse_methods};
use crate::report::csv::Float;
use crate::scene::SceneError;
use crate::scene::limits::{self, MAX_BISECTIONS, MAX_DRIFT_STEPS, MIN_PEER_TOLERANCE};
use crate::scene::overrides::method_help;
use crate::stress::drift::MIN_DRIFT_STEPS;

/// A stress case: a built-in scene and the horizon of its stability probes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StressCase {
    /// Built-in scene name.
    pub scene: &'static str,
    /// Length of the time interval each stability probe integrates.
    pub probe_time: f64,
}

/// The stress cases of `svi stress`, in table order.
pub const CASES: &[StressCase] = &[
    StressCase {
        scene: "oscillator",
        probe_time: 100.0,
    },
    StressCase {
        scene: "kepler-long",
        probe_time: 200.0,
    },
    StressCase {
        scene: "kepler-e0.9",
        probe_time: 63.0,
    },
    StressCase {
        scene: "kepler-e0.99",
        probe_time: 63.0,
    },
    StressCase {
        scene: "stiff-spring-pendulum",
        probe_time: 10.0,
    },
    StressCase {
        scene: "stiff-spring-pendulum-coarse",
        probe_time: 10.0,
    },
    StressCase {
        scene: "stiff-spring-pendulum-multiscale",
        probe_time: 10.0,
    },
    StressCase {
        scene: "double-pendulum-chaotic",
        probe_time: 20.0,
    },
];

/// The default method list of `svi stress`.
pub const DEFAULT_METHODS: &str = "svi:6,sc:6,midpoint,verlet,dop853";

/// Bisections refining each stability boundary by default (`--bisections`).
pub const DEFAULT_BISECTIONS: usize = 5;

/// DOP853's rtol = atol by default (`--tolerance`).
pub const DEFAULT_TOLERANCE: f64 = 1e-10;

/// `svi stress`'s arguments (parsed by the binary, and by tests as the binary does).
#[derive(Debug, Clone, PartialEq, clap::Args)]
pub struct StressArgs {
    /// Stress scenes, comma-separated [default: all of them].
    #[arg(long, value_delimiter = ',')]
    pub cases: Vec<String>,
    /// Methods, comma-separated: NAME, NAME:P or NAME:P/M (see --help), their adaptive
    /// modes METHOD@MONITOR, METHOD@sem and METHOD@step, and dop853.
    #[arg(
        long,
        value_name = "LIST",
        default_value = DEFAULT_METHODS,
        long_help = method_help(
            "Methods, comma-separated: the library's; their adaptive modes METHOD@MONITOR \
             (time-reparametrised, Δτ in place of h), METHOD@sem (symplectic-energy-momentum, \
             the first step in place of h) and METHOD@step (step doubling at --tolerance, drift \
             only); and dop853 (ode_solvers' DOP853, drift only)."
        )
    )]
    pub methods: String,
    /// Steps of the long run of each method.
    #[arg(
        long,
        default_value_t = 1_000_000,
        allow_hyphen_values = true,
        help = format!(
            "Steps of the long run of each method, {} to {MAX_DRIFT_STEPS}",
            MIN_DRIFT_STEPS
        )
    )]
    pub steps: usize,
    /// Bisections refining each stability boundary.
    #[arg(
        long,
        allow_hyphen_values = true,
        help = format!(
            "Bisections refining each stability boundary, 0 to {MAX_BISECTIONS} [default: {}]; \
             not with dop853 alone (it has no boundary)",
            DEFAULT_BISECTIONS
        )
    )]
    pub bisections: Option<usize>,
    /// DOP853's rtol = atol, and step doubling's tolerance.
    #[arg(
        long,
        allow_hyphen_values = true,
        help = format!(
            "DOP853's rtol = atol and METHOD@step's tolerance, at least {} [default: {}]; \
             only with dop853 or METHOD@step in --methods",
            Float(MIN_PEER_TOLERANCE),
            Float(DEFAULT_TOLERANCE)
        )
    )]
    pub tolerance: Option<f64>,
    /// Directory for stress.md, stress.csv, windows.csv and drift.svg.
    #[arg(long, default_value = "stress-out")]
    pub out_dir: std::path::PathBuf,
}

impl StressArgs {
    /// The options these arguments ask for; an error names a method that is not known.
    pub fn options(&self) -> Result<StressOptions, SceneError> {
        Ok(StressOptions {
            cases: self.cases.clone(),
            methods: parse_methods(&self.methods)?,
            drift_steps: self.steps,
            bisections: self.bisections,
            tolerance: self.tolerance,
            verbose: true,
        })
    }
}

/// Options of [`stress`](crate::stress::case::stress).
#[derive(Debug, Clone, PartialEq)]
pub struct StressOptions {
    /// Scenes (names from [`CASES`]); empty: all.
    pub cases: Vec<String>,
    /// Methods: the library's (`svi:P/M`, `sc:P`, `verlet`, ...), their adaptive modes
    /// (`METHOD@MONITOR`, `METHOD@sem`, `METHOD@step`) and `dop853` (drift only).
    pub methods: Vec<BenchMethod>,
    /// Steps of the long run, [`MIN_DRIFT_STEPS`] to [`MAX_DRIFT_STEPS`].
    pub drift_steps: usize,
    /// Bisections refining each stability boundary, up to [`MAX_BISECTIONS`] (`None`:
    /// [`DEFAULT_BISECTIONS`]); set only with a library method.
    pub bisections: Option<usize>,
    /// DOP853's rtol = atol and step doubling's tolerance (`None`: [`DEFAULT_TOLERANCE`]);
    /// set only with `dop853` or `METHOD@step`.
    pub tolerance: Option<f64>,
    /// Print progress to stderr.
    pub verbose: bool,
}

impl Default for StressOptions {
    fn default() -> Self {
        StressOptions {
            cases: Vec::new(),
            methods: parse_methods(DEFAULT_METHODS).unwrap_or_default(),
            drift_steps: 1_000_000,
            bisections: None,
            tolerance: None,
            verbose: false,
        }
    }
}

impl StressOptions {
    /// The bisections refining each stability boundary.
    pub fn bisections(&self) -> usize {
        self.bisections.unwrap_or(DEFAULT_BISECTIONS)
    }

    /// DOP853's rtol = atol, and step doubling's tolerance.
    pub fn tolerance(&self) -> f64 {
        self.tolerance.unwrap_or(DEFAULT_TOLERANCE)
    }

    /// Check every option before anything runs: known stress cases, methods `svi stress`
    /// can use, counts within their caps ([`crate::scene::limits`]), and `--bisections` and
    /// `--tolerance` only with the methods they apply to. An error names the option.
    pub fn check(&self) -> Result<(), SceneError> {
        for name in &self.cases {
            if !CASES.iter().any(|case| case.scene == name) {
                return Err(SceneError::UnknownStressCase {
                    name: name.clone(),
                    known: CASES.iter().map(|case| case.scene).collect(),
                });
            }
        }
        if self.methods.is_empty() {
            return Err(SceneError::InvalidOption {
                option: "--methods",
                reason: "no method given".into(),
            });
        }
        if let Some(&peer) = self.methods.iter().find(|method| {
            matches!(
                method,
                BenchMethod::Dopri5 | BenchMethod::Radau5 | BenchMethod::Molly
            )
        }) {
            return Err(peer_not_applicable(peer));
        }
        limits::count(
            "--steps",
            self.drift_steps,
            MIN_DRIFT_STEPS,
            MAX_DRIFT_STEPS,
            "steps",
        )?;
        // Dopri5, Radau5 and molly are refused above: the methods left without steps are
        // dop853 and METHOD@step, which take --tolerance.
        let searched = self.methods.iter().any(BenchMethod::takes_steps);
        let tolerance_driven = self.methods.iter().any(|method| !method.takes_steps());
        if let Some(bisections) = self.bisections {
            limits::count("--bisections", bisections, 0, MAX_BISECTIONS, "bisections")?;
            if !searched {
                return Err(SceneError::NotApplicable {
                    option: "--bisections",
                    reason: "refines the step limits of the library's stepped methods, and \
                             --methods lists only dop853 and METHOD@step (which have none)"
                        .into(),
                });
            }
        }
        if let Some(tolerance) = self.tolerance {
            limits::peer_tolerance("--tolerance", tolerance)?;
            if !tolerance_driven {
                return Err(SceneError::NotApplicable {
                    option: "--tolerance",
                    reason: "sets the tolerance of dop853 and METHOD@step, and --methods has \
                             neither"
                        .into(),
                });
            }
        }
        Ok(())
    }
}

/// A peer other than `dop853` (`dopri5`, `radau5`, `molly`) in `svi stress --methods`.
pub(super) fn peer_not_applicable(peer: BenchMethod) -> SceneError {
    SceneError::MethodNotApplicable {
        method: peer.to_string(),
        reason: "svi stress compares with dop853 only".into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_peers_other_than_dop853_are_refused_by_name() {
        // dopri5, radau5 and molly alike: the same error, naming the peer, before anything
        // runs.
        for (methods, named) in [
            ("verlet,dopri5", "dopri5"),
            ("radau5", "radau5"),
            ("dop853,radau5,dopri5", "radau5"),
            ("verlet,molly", "molly"),
        ] {
            let options = StressOptions {
                methods: parse_methods(methods).unwrap(),
                ..StressOptions::default()
            };
            let error = options.check().unwrap_err();
            assert!(
                matches!(&error, SceneError::MethodNotApplicable { method, reason }
                    if method == named && reason == "svi stress compares with dop853 only"),
                "{methods}: {error}"
            );
        }
    }
}
