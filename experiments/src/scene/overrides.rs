//! Scene fields set from the command line (`svi run`'s flags) and the help of method options.

use std::path::PathBuf;

use svi::method::registry;
use svi::model::reparametrized::MonitorSpec;

use crate::report::csv::Float;
use crate::scene::error::SceneError;
use crate::scene::method::SceneMethod;
use crate::scene::schema::{AdaptMode, Diagnostic, FormName, RecoveryKind};

/// The help of an option taking a method: `intro`, then the grammar and every method.
pub fn method_help(intro: &str) -> String {
    format!("{intro}\n\n{}", registry::grammar_help())
}

/// The help of `--method` of the commands that run scenes: [`method_help`] and the
/// constrained methods of scenes with constraints.
pub fn run_method_help(intro: &str) -> String {
    format!(
        "{}\n{}",
        method_help(intro),
        crate::scene::method::constrained_help()
    )
}

/// `a,b,c` of diagnostics' names.
pub fn diagnostic_names(diagnostics: &[Diagnostic]) -> String {
    use clap::ValueEnum;
    let names: Vec<String> = diagnostics
        .iter()
        .filter_map(|d| d.to_possible_value())
        .map(|value| value.get_name().to_string())
        .collect();
    names.join(",")
}

/// The help of `--diagnostics`, with the default of `svi run` (a [`Scene`](crate::Scene)
/// without `output.diagnostics`) or of `svi ensemble`.
pub fn diagnostics_help(default: &[Diagnostic]) -> String {
    format!(
        "Diagnostics to compute, comma-separated, or none [default: {}]",
        diagnostic_names(default)
    )
}

/// The long help of `--diagnostics`: [`diagnostics_help`] and what `none` means.
pub fn diagnostics_long_help(default: &[Diagnostic]) -> String {
    format!(
        "{}\n\nnone computes no per-step diagnostic at all (on rigid bodies also no invariant \
         and orthogonality errors); their summary fields are null.",
        diagnostics_help(default)
    )
}

/// The help of `--tol`, with the library's default tolerance.
pub fn tol_help() -> String {
    format!(
        "Target final error of --adapt step and --adapt degree [default: {}]; an error without \
         them",
        Float(svi::solve::SolveOptions::default().tol.unwrap_or(f64::NAN))
    )
}

/// The help of `--monitor`, with the default monitor.
pub fn monitor_help() -> String {
    format!(
        "The monitor g(q) > 0 of --adapt reparam: sundman:ALPHA is g = |q|^ALPHA for a central \
         force about the origin (ALPHA = 1.5 or 1 for Kepler orbits); force:BETA is \
         g = |∂L/∂q(q, 0)|^(−BETA), the force at rest derived from the model (force:0.75 is \
         sundman:1.5 for an inverse-square force); potential is g = 1/L(q, 0) = −1/V(q), with \
         verlet, yoshida4, kahan-li6 or kahan-li8 on a constant-mass model the explicit \
         logarithmic-Hamiltonian splitting [default: {}]",
        MonitorSpec::default()
    )
}

/// The help of `--max-steps`, with the cap (the default) of the library.
pub fn max_steps_help() -> String {
    let cap = svi::stepping::grid::MAX_STEPS;
    format!(
        "Most steps of the run, 1 to {cap} [default: {cap}]: an adaptive run (--adapt step, \
         degree, sem, reparam) that needs more stops with the error too_many_steps and the run \
         so far; a fixed-step run that needs more is rejected before it starts"
    )
}

/// The help of `--sensitivity`, with the models whose parameters can be differentiated and
/// their parameters ([`svi_models::PARAMETRIC_MODEL_NAMES`]).
pub fn sensitivity_help() -> String {
    /// The parameter names of a visited model.
    struct Names;
    impl svi_models::ParametricModelVisitor for Names {
        type Output = Vec<String>;
        fn visit<M: svi_models::ZooModel<N> + svi::Parametric<N>, N: svi::Dimension>(
            self,
            model: M,
        ) -> Vec<String>
        where
            nalgebra::DefaultAllocator:
                nalgebra::allocator::Allocator<N> + nalgebra::allocator::Allocator<N, N>,
        {
            model.parameter_names()
        }
    }
    let models = svi_models::PARAMETRIC_MODEL_NAMES
        .iter()
        .map(|&name| {
            let names = svi_models::visit_parametric_model(name, Names).unwrap_or_default();
            format!("{name}: {}", names.join(", "))
        })
        .collect::<Vec<_>>()
        .join("; ");
    format!(
        "Derivatives of the state with respect to the initial state and parameters, \
         comma-separated: q0, v0 (p0 for a start given in momenta) and parameter names; the \
         exact derivatives of the method's fixed steps (models and their parameters: {models})"
    )
}

/// The flags of every command that runs a scene (`svi run`, `svi ensemble`): the method, the
/// step and horizon, the diagnostics and the run's options. A field here is a flag of both
/// commands and a keyword of the Python package's `svi.run`, `svi.solve` and `svi.ensemble`.
#[derive(Debug, Clone, Default, PartialEq, clap::Args)]
pub struct RunFlags {
    /// Integration method: NAME, NAME:P or NAME:P/M, e.g. svi:7/6, sc:9, verlet.
    #[arg(
        long,
        value_name = "METHOD",
        long_help = run_method_help(
            "Integration method (default: the scene's). Rigid-body scenes take lie-svi or \
             lie-svi-reduced; scenes with constraints a constrained method (default rattle)."
        )
    )]
    pub method: Option<SceneMethod>,
    /// Number of Chebyshev–Gauss–Lobatto points (svi, sc, lie-svi), on top of --method.
    #[arg(long, value_name = "N", allow_hyphen_values = true)]
    pub points: Option<usize>,
    /// Number of Gauss–Legendre quadrature points (svi, lie-svi), on top of --method.
    #[arg(long, value_name = "M", allow_hyphen_values = true)]
    pub quadrature: Option<usize>,
    /// Step size (not with --adapt step, which chooses its own steps).
    #[arg(long = "h", value_name = "H", allow_hyphen_values = true)]
    pub h: Option<f64>,
    /// Final time.
    #[arg(long, value_name = "T", allow_hyphen_values = true)]
    pub t_end: Option<f64>,
    /// Diagnostics to compute, comma-separated, or none.
    #[arg(
        long,
        value_enum,
        value_name = "LIST",
        value_delimiter = ',',
        help = diagnostics_help(&crate::Scene::DEFAULT_DIAGNOSTICS),
        long_help = diagnostics_long_help(&crate::Scene::DEFAULT_DIAGNOSTICS)
    )]
    pub diagnostics: Option<Vec<Diagnostic>>,
    /// Adaptivity (the modes below; the default: none).
    #[arg(long, value_enum)]
    pub adapt: Option<AdaptMode>,
    /// Target final error of --adapt step and --adapt degree.
    #[arg(long, value_name = "TOL", allow_hyphen_values = true, help = tol_help())]
    pub tol: Option<f64>,
    /// The monitor g(q) > 0 of --adapt reparam.
    #[arg(long, value_name = "MONITOR", help = monitor_help())]
    pub monitor: Option<MonitorSpec>,
    /// Recovery policy for failed steps (fixed steps only: the adaptive modes retry failed
    /// steps themselves).
    #[arg(long, value_enum)]
    pub recovery: Option<RecoveryKind>,
    /// Stop once a state component exceeds this in absolute value.
    #[arg(long, value_name = "LIMIT", allow_hyphen_values = true)]
    pub divergence_limit: Option<f64>,
    /// Most steps of the run.
    #[arg(long, value_name = "STEPS", allow_hyphen_values = true, help = max_steps_help())]
    pub max_steps: Option<usize>,
    /// Form of the Lie-group integrator for rigid-body scenes: full or reduced.
    #[arg(long, value_enum, value_name = "FORM")]
    pub form: Option<FormName>,
    /// Chaos indicators from the method's exact tangent maps, comma-separated (fixed steps on
    /// ℝᴺ): megno, lyapunov (maximal exponent), spectrum (all 2N exponents), sali, gali (GALI_N).
    #[arg(long, value_enum, value_name = "LIST", value_delimiter = ',')]
    pub indicators: Option<Vec<crate::scene::schema::Indicator>>,
    /// Derivatives of the state with respect to the initial state and parameters,
    /// comma-separated: q0, v0 (p0 for a start given in momenta) and parameter names.
    #[arg(long, value_name = "LIST", value_delimiter = ',', help = sensitivity_help())]
    pub sensitivity: Option<Vec<String>>,
    /// Report the sensitivities every K steps besides the start and the end.
    #[arg(long, value_name = "K")]
    pub sensitivity_every: Option<usize>,
}

/// Scene fields set from the command line: the [`RunFlags`], and the model's parameters and
/// outputs of one run.
#[derive(Debug, Clone, Default, PartialEq, clap::Args)]
pub struct Overrides {
    /// The flags of every command that runs a scene.
    #[command(flatten)]
    pub run: RunFlags,
    /// Model parameter (repeatable), e.g. `--param e=0.9`.
    #[arg(long = "param", value_name = "NAME=VALUE", value_parser = parse_parameter)]
    pub parameters: Vec<(String, f64)>,
    /// Keep every K-th step of the trajectory (with --out, without --output-times; default 1).
    #[arg(long, value_name = "K", allow_hyphen_values = true)]
    pub every: Option<usize>,
    /// Write the trajectory as CSV to FILE.
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Draw the trajectory written by --out as an SVG line chart to FILE: every column
    /// against t (on chains the energy and the observables, e.g. FPUT's mode energies).
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
    /// Report the states at these times, comma-separated (dense output); with --out the
    /// trajectory holds them instead of the steps.
    #[arg(
        long,
        value_name = "LIST",
        value_delimiter = ',',
        allow_hyphen_values = true
    )]
    pub output_times: Option<Vec<f64>>,
    /// Add the Lagrange multipliers of a constrained run to the trajectory (--out), one column
    /// lambda_1, … per constraint (--multipliers alone is --multipliers=true).
    #[arg(
        long,
        value_name = "BOOL",
        num_args = 0..=1,
        require_equals = true,
        default_missing_value = "true"
    )]
    pub multipliers: Option<bool>,
    /// Locate the zeros of a function g(t, q, q̇) of the model's names (repeatable):
    /// `[NAME:] G [@up|@down|@both] [@terminal]`, e.g. "pericentre: x*vx + y*vy @up".
    #[arg(long, value_name = "EVENT")]
    pub event: Vec<crate::scene::events::EventSpec>,
    /// Poincaré section COORDINATE=VALUE[,VARIABLE>VALUE], e.g. "y=0,vy>0" (or "q2=0,v2>0"):
    /// --out writes its points instead of the trajectory, --plot draws them.
    #[arg(long, value_name = "SECTION")]
    pub section: Option<crate::scene::events::SectionSpec>,
    /// Write the events located by --event as CSV to FILE, one row per event:
    /// event,t,q_…,v_…,p_… (also after a run that failed).
    #[arg(long, value_name = "FILE")]
    pub events_out: Option<PathBuf>,
}

/// The kind of value a run option takes, read from its flag's parser: what a front door that
/// names options (the Python package's keyword arguments) checks a value against.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OptionKind {
    /// A number (`--h`, `--tol`).
    Real,
    /// A whole number, 0 or more (`--points`, `--max-steps`).
    Count,
    /// A word parsed by the flag (`--method`, `--adapt`).
    Text,
    /// A list of numbers (`--output-times`).
    Reals,
    /// A list of words (`--diagnostics`).
    Names,
    /// A list of texts, each the argument of one repetition of the flag (`--event`).
    Texts,
    /// True or false (`--multipliers`).
    Flag,
}

impl OptionKind {
    /// The kind's name: `real`, `count`, `text`, `reals`, `names`, `texts`, `flag`.
    pub fn name(self) -> &'static str {
        match self {
            OptionKind::Real => "real",
            OptionKind::Count => "count",
            OptionKind::Text => "text",
            OptionKind::Reals => "reals",
            OptionKind::Names => "names",
            OptionKind::Texts => "texts",
            OptionKind::Flag => "flag",
        }
    }
}

/// A value of a run option given by name, of the option's [`OptionKind`].
#[derive(Debug, Clone, PartialEq)]
pub enum OptionValue {
    /// A whole number.
    Count(u64),
    /// A number.
    Real(f64),
    /// A word.
    Text(String),
    /// Numbers.
    Reals(Vec<f64>),
    /// Words.
    Names(Vec<String>),
    /// Texts, one per repetition of the flag.
    Texts(Vec<String>),
    /// True or false.
    Flag(bool),
}

impl OptionValue {
    /// The value as the flag's arguments: numbers in exponent form (exact), lists
    /// comma-separated, texts one argument each (the flag repeated).
    fn arguments(&self) -> Vec<String> {
        let join = |items: Vec<String>| items.join(",");
        let one = match self {
            OptionValue::Count(n) => n.to_string(),
            OptionValue::Real(x) => format!("{x:e}"),
            OptionValue::Text(text) => text.clone(),
            OptionValue::Reals(xs) => join(xs.iter().map(|x| format!("{x:e}")).collect()),
            OptionValue::Names(names) => join(names.clone()),
            OptionValue::Texts(texts) => return texts.clone(),
            OptionValue::Flag(flag) => flag.to_string(),
        };
        vec![one]
    }
}

/// `svi run`'s flags as a command of their own, parsed for options given by name.
#[derive(Debug, clap::Parser)]
#[command(name = "svi run")]
struct Named {
    #[command(flatten)]
    overrides: Overrides,
}

impl Overrides {
    /// Every option of `svi run` by its name (the flag's id: `t_end` for `--t-end`,
    /// `parameters` for `--param`) and the kind of value it takes. One field of [`Overrides`]
    /// is one flag of the command line and one keyword of the Python package.
    pub fn options() -> Vec<(String, OptionKind)> {
        use clap::CommandFactory;
        use clap::builder::ValueParser;
        let real = ValueParser::from(clap::value_parser!(f64)).type_id();
        let count = ValueParser::from(clap::value_parser!(usize)).type_id();
        let flag = ValueParser::bool().type_id();
        let command = Named::command();
        command
            .get_arguments()
            .filter(|arg| arg.get_long().is_some())
            .map(|arg| {
                let list = arg.get_value_delimiter().is_some();
                let repeated = matches!(arg.get_action(), clap::ArgAction::Append);
                let parsed = arg.get_value_parser().type_id();
                let kind = if parsed == real {
                    if list {
                        OptionKind::Reals
                    } else {
                        OptionKind::Real
                    }
                } else if parsed == count {
                    OptionKind::Count
                } else if parsed == flag {
                    OptionKind::Flag
                } else if list {
                    OptionKind::Names
                } else if repeated {
                    OptionKind::Texts
                } else {
                    OptionKind::Text
                };
                (arg.get_id().to_string(), kind)
            })
            .collect()
    }

    /// The overrides of options given by name ([`Overrides::options`]), parsed by the
    /// parser of `svi run`'s flags: the same values, defaults and errors as on the command
    /// line.
    pub fn from_named(options: &[(String, OptionValue)]) -> Result<Overrides, SceneError> {
        use clap::{CommandFactory, FromArgMatches};
        let command = Named::command();
        let mut tokens = vec!["svi run".to_string()];
        for (name, value) in options {
            let long = command
                .get_arguments()
                .find(|arg| arg.get_id() == name.as_str())
                .and_then(|arg| arg.get_long())
                .ok_or_else(|| SceneError::InvalidOption {
                    option: "option",
                    reason: format!(
                        "unknown option '{name}' (known: {})",
                        Overrides::options()
                            .into_iter()
                            .map(|(name, _)| name)
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                })?;
            for argument in value.arguments() {
                tokens.push(format!("--{long}={argument}"));
            }
        }
        let invalid = |error: clap::Error| SceneError::InvalidOption {
            option: "option",
            reason: error
                .to_string()
                .lines()
                .next()
                .unwrap_or("rejected")
                .trim_start_matches("error: ")
                .to_string(),
        };
        let matches = command.try_get_matches_from(tokens).map_err(invalid)?;
        Named::from_arg_matches(&matches)
            .map(|named| named.overrides)
            .map_err(invalid)
    }
}

/// Parse `NAME=VALUE` (the argument of `--param`).
pub fn parse_parameter(text: &str) -> Result<(String, f64), SceneError> {
    let malformed = |reason: &str| SceneError::MalformedParameter {
        text: text.into(),
        reason: reason.into(),
    };
    let (name, value) = text
        .split_once('=')
        .ok_or_else(|| malformed("expected NAME=VALUE"))?;
    let name = name.trim();
    if name.is_empty() {
        return Err(malformed("the name is empty (expected NAME=VALUE)"));
    }
    let value = value
        .trim()
        .parse::<f64>()
        .map_err(|_| malformed(&format!("'{}' is not a number", value.trim())))?;
    Ok((name.into(), value))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn options_given_by_name_are_the_flags_parsed_by_the_command_line_parser() {
        use clap::Parser;
        let kinds: std::collections::BTreeMap<String, OptionKind> =
            Overrides::options().into_iter().collect();
        assert_eq!(kinds["h"], OptionKind::Real);
        assert_eq!(kinds["max_steps"], OptionKind::Count);
        assert_eq!(kinds["method"], OptionKind::Text);
        assert_eq!(kinds["output_times"], OptionKind::Reals);
        assert_eq!(kinds["diagnostics"], OptionKind::Names);
        assert_eq!(kinds["event"], OptionKind::Texts);
        let named = Overrides::from_named(&[
            ("method".into(), OptionValue::Text("svi:7/6".into())),
            ("h".into(), OptionValue::Real(0.1)),
            ("t_end".into(), OptionValue::Real(-1e-300)),
            ("max_steps".into(), OptionValue::Count(7)),
            (
                "output_times".into(),
                OptionValue::Reals(vec![0.5, 1.0 / 3.0]),
            ),
            (
                "diagnostics".into(),
                OptionValue::Names(vec!["energy".into(), "momentum".into()]),
            ),
            ("adapt".into(), OptionValue::Text("degree".into())),
            (
                "event".into(),
                OptionValue::Texts(vec!["up: x @up".into(), "y, z".into()]),
            ),
        ])
        .unwrap();
        let third = format!("{:e}", 1.0 / 3.0);
        let flags = Named::try_parse_from([
            "svi run",
            "--method",
            "svi:7/6",
            "--h",
            "0.1",
            "--t-end",
            "-1e-300",
            "--max-steps",
            "7",
            "--output-times",
            &format!("0.5,{third}"),
            "--diagnostics",
            "energy,momentum",
            "--adapt",
            "degree",
            "--event",
            "up: x @up",
            "--event",
            "y, z",
        ])
        .unwrap();
        assert_eq!(named, flags.overrides);
        assert_eq!(named.event.len(), 2);
        assert_eq!(named.output_times.as_ref().unwrap()[1], 1.0 / 3.0);
        for (name, value, says) in [
            ("adapt", OptionValue::Text("bogus".into()), "--adapt"),
            ("tol", OptionValue::Text("abc".into()), "--tol"),
            (
                "frobnicate",
                OptionValue::Count(1),
                "unknown option 'frobnicate'",
            ),
        ] {
            let error = Overrides::from_named(&[(name.into(), value)]).unwrap_err();
            assert!(error.to_string().contains(says), "{error}");
            assert!(error.is_bad_input());
        }
    }

    #[test]
    fn parameters_parse_as_name_equals_number() {
        assert_eq!(parse_parameter("e=0.9").unwrap(), ("e".into(), 0.9));
        assert_eq!(parse_parameter(" g = 9.81 ").unwrap(), ("g".into(), 9.81));
        assert_eq!(parse_parameter("k=1e4").unwrap(), ("k".into(), 1e4));
        for bad in ["e", "e=", "=1", "e=abc", "e:1"] {
            let error = parse_parameter(bad).unwrap_err();
            assert!(
                matches!(&error, SceneError::MalformedParameter { text, .. } if text == bad),
                "{bad}: {error}"
            );
        }
    }
}
