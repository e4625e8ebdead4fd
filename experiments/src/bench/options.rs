//! The options of a work–precision sweep: `svi bench`'s arguments as the command line parses
//! them, their defaults, and every check of them before anything runs.

use crate::bench::method::{BenchMethod, parse_methods};
use crate::bench::peers::RADAU5_TOLERANCE_FLOOR;
use crate::report::csv;
use crate::scene::SceneError;
use crate::scene::limits::{
    self, MAX_BATCH_SECONDS, MAX_BATCHES, MAX_RUN_SECONDS, MAX_STEPS, MIN_PEER_TOLERANCE,
};
use crate::scene::overrides::{Overrides, RunFlags, method_help, parse_parameter};

/// `svi bench`'s arguments (parsed by the binary, and by tests as the binary does).
#[derive(Debug, Clone, PartialEq, clap::Args)]
pub struct BenchArgs {
    /// Built-in scene or scene file [default: kepler].
    pub scene: Option<String>,
    /// Methods, comma-separated: NAME, NAME:P or NAME:P/M (see --help), dop853, dopri5,
    /// radau5, molly.
    #[arg(
        long,
        value_name = "LIST",
        default_value = DEFAULT_METHODS,
        long_help = method_help(
            "Methods, comma-separated: the library's (for models on ℝᴺ), the library's with \
             an adaptive mode — METHOD@MONITOR reparametrised in time (fixed steps in τ, dt = \
             g(q) dτ, e.g. svi:9/8@sundman:1; see svi run --monitor), METHOD@step step \
             doubling, METHOD@sem steps fixed by discrete energy conservation (svi; swept \
             over the first step) —, the adaptive peers dop853 and dopri5 (ode_solvers' \
             DOP853 and Dopri5), radau5 (differential-equations' Radau IIA of order 5, \
             the stiff solver, with the exact Jacobian by automatic differentiation), and \
             molly (the mollified impulse method of García-Archilla, Sanz-Serna & Skeel, a \
             trigonometric integrator with fixed steps over the fast spring, order 2; the \
             spring pendulum only). On a chain or a text model the default list keeps only \
             the library's methods without an adaptive mode, the ones such a model runs."
        )
    )]
    pub methods: String,
    /// Model parameter NAME=VALUE (repeatable).
    #[arg(long = "param", value_name = "NAME=VALUE", value_parser = parse_parameter)]
    pub parameters: Vec<(String, f64)>,
    /// Horizon (overrides the scene's), at most [`MAX_STEPS`] steps of the model's default
    /// step.
    #[arg(
        long,
        allow_hyphen_values = true,
        help = format!(
            "Horizon (overrides the scene's), at most {MAX_STEPS} steps of the model's default \
             step"
        )
    )]
    pub t_end: Option<f64>,
    /// Stop a method's sweep once its final error is below this.
    #[arg(
        long,
        allow_hyphen_values = true,
        help = format!(
            "Stop a method's sweep once its final error is below this positive number \
             [default: {}]; only when a method sweeps",
            csv::Float(DEFAULT_TARGET)
        )
    )]
    pub target: Option<f64>,
    /// Stop a method's sweep after a point whose single run takes longer (seconds).
    #[arg(
        long,
        allow_hyphen_values = true,
        help = format!(
            "Stop a method's sweep after a point whose single run takes longer, in seconds \
             (above 0, at most {}) [default: {}]; only when a method sweeps",
            csv::Float(MAX_RUN_SECONDS),
            csv::Float(DEFAULT_MAX_RUN)
        )
    )]
    pub max_run: Option<f64>,
    /// Timing batches per point (median reported).
    #[arg(
        long,
        default_value_t = 5,
        allow_hyphen_values = true,
        help = format!("Timing batches per point (median reported), 1 to {MAX_BATCHES}")
    )]
    pub batches: usize,
    /// Minimum duration of a timing batch (seconds).
    #[arg(
        long,
        default_value_t = 0.2,
        allow_hyphen_values = true,
        help = format!(
            "Minimum duration of a timing batch, in seconds (0: one run per batch; at most {})",
            csv::Float(MAX_BATCH_SECONDS)
        )
    )]
    pub min_batch: f64,
    /// Run the fixed-step methods (and METHOD@MONITOR, in τ-steps, and molly) at these step
    /// counts instead of sweeping them.
    #[arg(
        long,
        value_delimiter = ',',
        allow_hyphen_values = true,
        help = format!(
            "Run the fixed-step methods (and METHOD@MONITOR, in steps of τ, and molly) at these \
             step counts (each 1 to {MAX_STEPS}) instead of sweeping them"
        )
    )]
    pub steps: Vec<usize>,
    /// Run the adaptive peers (dop853, dopri5, radau5) and METHOD@step at these tolerances
    /// instead of sweeping them.
    #[arg(
        long,
        value_delimiter = ',',
        allow_hyphen_values = true,
        help = format!(
            "Run the adaptive peers (dop853, dopri5, radau5) and METHOD@step at these \
             tolerances (each at least {}; radau5: above {}) instead of sweeping them",
            csv::Float(MIN_PEER_TOLERANCE),
            csv::Float(RADAU5_TOLERANCE_FLOOR)
        )
    )]
    pub tolerances: Vec<f64>,
    /// Measure the final error in this one coordinate of the model (e.g. theta) instead of
    /// the Euclidean position error.
    #[arg(long, value_name = "NAME")]
    pub coordinate: Option<String>,
    /// Directory for `<scene>.csv` and `<scene>.svg`.
    #[arg(long, default_value = "bench-out")]
    pub out_dir: std::path::PathBuf,
}

impl BenchArgs {
    /// The overrides (parameters, horizon) and the options of the sweep these arguments ask
    /// for; an error names a method that is not known.
    pub fn options(&self) -> Result<(Overrides, BenchOptions), SceneError> {
        let overrides = Overrides {
            run: RunFlags {
                t_end: self.t_end,
                ..RunFlags::default()
            },
            parameters: self.parameters.clone(),
            ..Overrides::default()
        };
        let options = BenchOptions {
            methods: parse_methods(&self.methods)?,
            target: self.target,
            max_run: self.max_run,
            batches: self.batches,
            min_batch: self.min_batch,
            steps: self.steps.clone(),
            tolerances: self.tolerances.clone(),
            coordinate: self.coordinate.clone(),
            verbose: true,
        };
        Ok((overrides, options))
    }
}

/// Options of a work–precision sweep.
#[derive(Debug, Clone, PartialEq)]
pub struct BenchOptions {
    /// Methods to sweep.
    pub methods: Vec<BenchMethod>,
    /// Stop a sweep once the final error is below this (`None`: [`DEFAULT_TARGET`]); set
    /// only when a method sweeps.
    pub target: Option<f64>,
    /// Stop a sweep after a point whose single run takes longer, in seconds, up to
    /// [`MAX_RUN_SECONDS`] (`None`: [`DEFAULT_MAX_RUN`]); set only when a method sweeps.
    pub max_run: Option<f64>,
    /// Timing batches per point (the median is reported), 1 to [`MAX_BATCHES`].
    pub batches: usize,
    /// Minimum duration of one batch, in seconds, 0 to [`MAX_BATCH_SECONDS`] (0: one run
    /// per batch).
    pub min_batch: f64,
    /// Step counts, 1 to [`MAX_STEPS`], at which to run the fixed-step methods instead of
    /// sweeping them (empty: sweep).
    pub steps: Vec<usize>,
    /// Tolerances at which to run the adaptive peers instead of sweeping them (empty: sweep).
    pub tolerances: Vec<f64>,
    /// The coordinate (one of the model's coordinate names) the final error is measured in
    /// (`None`: the Euclidean position error).
    pub coordinate: Option<String>,
    /// Print one line per point to stderr.
    pub verbose: bool,
}

impl Default for BenchOptions {
    fn default() -> Self {
        BenchOptions {
            methods: parse_methods(DEFAULT_METHODS).unwrap_or_default(),
            target: None,
            max_run: None,
            batches: 5,
            min_batch: 0.2,
            steps: Vec::new(),
            tolerances: Vec::new(),
            coordinate: None,
            verbose: false,
        }
    }
}

/// The default method list of `svi bench`.
pub const DEFAULT_METHODS: &str =
    "svi:7/6,svi:6/5,svi:9/8,svi:6/12,sc:9,svi:9/8@sundman:1,svi:7/6@step,dop853,dopri5";

/// The error at which a sweep stops by default (`--target`).
pub const DEFAULT_TARGET: f64 = 1e-13;

/// The single-run time, in seconds, after which a sweep stops by default (`--max-run`).
pub const DEFAULT_MAX_RUN: f64 = 2.0;

impl BenchOptions {
    /// The error at which a sweep stops.
    pub fn target(&self) -> f64 {
        self.target.unwrap_or(DEFAULT_TARGET)
    }

    /// The single-run time after which a sweep stops.
    pub fn max_run(&self) -> f64 {
        self.max_run.unwrap_or(DEFAULT_MAX_RUN)
    }

    /// Check every option against its range ([`crate::scene::limits`]), and that each one
    /// set applies to some method: `--steps` to the library's methods, `--tolerances` to the
    /// peers, `--target` and `--max-run` to a sweep. An error names the option.
    pub fn check(&self) -> Result<(), SceneError> {
        if self.methods.is_empty() {
            return Err(SceneError::InvalidOption {
                option: "--methods",
                reason: "no method given".into(),
            });
        }
        limits::count("--batches", self.batches, 1, MAX_BATCHES, "timing batches")?;
        limits::seconds("--min-batch", self.min_batch, true, MAX_BATCH_SECONDS)?;
        if let Some(max_run) = self.max_run {
            limits::seconds("--max-run", max_run, false, MAX_RUN_SECONDS)?;
        }
        if let Some(target) = self.target {
            limits::positive("--target", target)?;
        }
        for &steps in &self.steps {
            limits::count("--steps", steps, 1, MAX_STEPS, "steps")?;
        }
        for &tol in &self.tolerances {
            limits::peer_tolerance("--tolerances", tol)?;
        }
        let below_radau5_floor = self
            .tolerances
            .iter()
            .find(|&&tol| tol <= RADAU5_TOLERANCE_FLOOR);
        if let Some(&tol) = below_radau5_floor
            && self.methods.contains(&BenchMethod::Radau5)
        {
            return Err(SceneError::InvalidOption {
                option: "--tolerances",
                reason: format!(
                    "{}; radau5 needs tolerances above {} (RADAU5 rejects rtol ≤ 10·uround)",
                    csv::Float(tol),
                    csv::Float(RADAU5_TOLERANCE_FLOOR)
                ),
            });
        }
        let fixed = self.methods.iter().any(BenchMethod::takes_steps);
        let peers = self.methods.iter().any(|method| !method.takes_steps());
        let not_applicable = |option, reason: &str| {
            Err(SceneError::NotApplicable {
                option,
                reason: reason.into(),
            })
        };
        if !self.steps.is_empty() && !fixed {
            return not_applicable(
                "--steps",
                "sets the step counts of the library's methods, and --methods lists only \
                 dop853, dopri5, radau5 or METHOD@step (set their --tolerances)",
            );
        }
        if !self.tolerances.is_empty() && !peers {
            return not_applicable(
                "--tolerances",
                "sets the tolerances of dop853, dopri5 and radau5 (and of METHOD@step), and \
                 the methods swept include none of them (--methods, or on a chain or a text \
                 model the default list, which keeps only the fixed-step methods)",
            );
        }
        let sweeps = (fixed && self.steps.is_empty()) || (peers && self.tolerances.is_empty());
        for (given, option) in [
            (self.target.is_some(), "--target"),
            (self.max_run.is_some(), "--max-run"),
        ] {
            if given && !sweeps {
                return not_applicable(
                    option,
                    "ends a sweep, and every method runs at the given --steps or --tolerances",
                );
            }
        }
        Ok(())
    }
}
