//! The methods a sweep compares (`--methods`: the library's, their adaptive modes, the
//! peers), and how a library method runs in its mode, in `svi bench` and in `svi stress`.

use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, OVector};
use std::fmt;
use std::str::FromStr;
use svi::model::reparametrized::MonitorSpec;
use svi::observer::Observer;
use svi::solve::{SolveOptions, Span};
use svi::{Dimension, Initial, Integrator, Method, MethodSpec, RunOptions};

use crate::bench::molly;
use crate::scene::SceneError;

/// A method configuration to sweep: a method of svi's registry, or a peer (`ode_solvers`'
/// DOP853 and Dopri5, `differential-equations`' Radau5, the mollified impulse method on the
/// spring pendulum).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum BenchMethod {
    /// A method of [`svi::method::registry::METHODS`] (fixed step).
    Library(MethodSpec),
    /// `ode_solvers`' DOP853 (adaptive, order 8).
    Dop853,
    /// `ode_solvers`' Dopri5 (adaptive, order 5).
    Dopri5,
    /// `differential-equations`' Radau IIA (adaptive, implicit, order 5): the stiff solver.
    Radau5,
    /// The mollified impulse method ([`crate::bench::molly`]; fixed step, order 2, spring
    /// pendulum only): the trigonometric peer.
    Molly,
    /// A library method in computational time τ with a monitor (`METHOD@MONITOR`).
    Reparam(MethodSpec, MonitorSpec),
    /// A library method with step doubling (`METHOD@step`).
    StepDoubling(MethodSpec),
    /// A library method with symplectic-energy-momentum steps (`METHOD@sem`), swept over
    /// its first step.
    Sem(MethodSpec),
}

impl BenchMethod {
    /// Whether the method is swept over step counts (the library's fixed-step methods, their
    /// τ-steps, SEM's first steps and `molly`), not tolerances.
    pub(crate) fn takes_steps(&self) -> bool {
        matches!(
            self,
            BenchMethod::Library(_)
                | BenchMethod::Reparam(..)
                | BenchMethod::Sem(_)
                | BenchMethod::Molly
        )
    }
}

impl fmt::Display for BenchMethod {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BenchMethod::Library(spec) => write!(f, "{spec}"),
            BenchMethod::Dop853 => write!(f, "dop853"),
            BenchMethod::Dopri5 => write!(f, "dopri5"),
            BenchMethod::Radau5 => write!(f, "radau5"),
            BenchMethod::Molly => write!(f, "{}", molly::NAME),
            BenchMethod::Reparam(spec, monitor) => write!(f, "{spec}@{monitor}"),
            BenchMethod::StepDoubling(spec) => write!(f, "{spec}@step"),
            BenchMethod::Sem(spec) => write!(f, "{spec}@sem"),
        }
    }
}

impl FromStr for BenchMethod {
    type Err = SceneError;

    /// `dop853`, `dopri5`, `radau5`, `molly`, or a library method written `name`, `name:P` or
    /// `name:P/M`, optionally followed by `@MONITOR` (reparametrised, e.g.
    /// `svi:9/8@sundman:1`), `@step` (step doubling) or `@sem` (symplectic-energy-momentum
    /// steps).
    fn from_str(text: &str) -> Result<Self, SceneError> {
        let text = text.trim();
        if let Some((method, mode)) = text.split_once('@') {
            let BenchMethod::Library(spec) = method.parse()? else {
                return Err(SceneError::BenchMethod { text: text.into() });
            };
            return match mode.trim() {
                "step" => Ok(BenchMethod::StepDoubling(spec)),
                "sem" => Ok(BenchMethod::Sem(spec)),
                monitor => Ok(BenchMethod::Reparam(spec, monitor.parse()?)),
            };
        }
        match text {
            "dop853" => Ok(BenchMethod::Dop853),
            "dopri5" => Ok(BenchMethod::Dopri5),
            "radau5" => Ok(BenchMethod::Radau5),
            molly::NAME => Ok(BenchMethod::Molly),
            _ => text.parse().map(BenchMethod::Library).map_err(|error| {
                let name = text.split(':').next().unwrap_or_default();
                match svi::method::registry::find(name) {
                    Some(_) => SceneError::Svi(error),
                    None => SceneError::BenchMethod { text: text.into() },
                }
            }),
        }
    }
}

/// Parse a comma-separated list of methods (empty items are skipped).
pub fn parse_methods(text: &str) -> Result<Vec<BenchMethod>, SceneError> {
    text.split(',')
        .filter(|s| !s.trim().is_empty())
        .map(str::parse)
        .collect()
}

/// How a library method runs in a sweep (and in `svi stress`).
#[derive(Debug, Clone, Copy)]
pub(crate) enum Mode {
    /// Fixed steps h, swept over step counts.
    Fixed,
    /// Fixed steps Δτ in computational time with a monitor, swept over τ-step counts.
    Reparam(MonitorSpec),
    /// Step doubling, swept over tolerances.
    StepDoubling,
    /// Symplectic-energy-momentum steps, swept over the first step's size.
    Sem,
}

impl Mode {
    /// The mode of a library method in `--methods` (`None` for the peers).
    pub(crate) fn of(method: &BenchMethod) -> Option<(MethodSpec, Mode)> {
        match *method {
            BenchMethod::Library(spec) => Some((spec, Mode::Fixed)),
            BenchMethod::Reparam(spec, monitor) => Some((spec, Mode::Reparam(monitor))),
            BenchMethod::StepDoubling(spec) => Some((spec, Mode::StepDoubling)),
            BenchMethod::Sem(spec) => Some((spec, Mode::Sem)),
            BenchMethod::Dop853
            | BenchMethod::Dopri5
            | BenchMethod::Radau5
            | BenchMethod::Molly => None,
        }
    }
}

/// One run of `integrator` in `mode` from `start` = (t0, initial) to `t_end`: at step (or Δτ)
/// `h`, or for step doubling at tolerance `h`, under `run` (the divergence limit); the final
/// position and the statistics.
pub(crate) fn run_mode<L: svi::Lagrangian<N>, Me: Method<N> + Clone, O, N: Dimension>(
    integrator: &Integrator<L, Me, svi::Euclidean<N>>,
    mode: Mode,
    ((t0, initial), t_end): &((f64, Initial<N>), f64),
    h: f64,
    run: &RunOptions,
    observer: &mut O,
) -> Result<(OVector<f64, N>, svi::Statistics), svi::Error>
where
    O: Observer<L, svi::PhasePoint<N>>,
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let (t0, t_end, initial) = (*t0, *t_end, initial.clone());
    let span = Span::new(t0, t_end);
    let with_run = |mut options: SolveOptions| {
        options.run = *run;
        options
    };
    let solution = match mode {
        Mode::Fixed => {
            let done = integrator.try_run(t0, initial, h, t_end, run, observer);
            let done = done.map_err(|failure| failure.error)?;
            return Ok((done.last.q, done.statistics));
        }
        Mode::Reparam(monitor) => integrator.try_solve_reparametrized(
            &monitor,
            &span,
            initial,
            &with_run(SolveOptions::fixed_step(h)),
            observer,
        ),
        Mode::StepDoubling => integrator.try_solve(
            &span,
            initial,
            &with_run(SolveOptions::step_adaptive(h)),
            observer,
        ),
        Mode::Sem => integrator.try_solve(
            &span,
            initial,
            &with_run(SolveOptions::energy_fitted(h)),
            observer,
        ),
    }
    .map_err(|failure| failure.error)?;
    Ok((solution.last.q, solution.statistics))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bench::options::DEFAULT_METHODS;

    #[test]
    fn method_specifications_parse_and_print_back() {
        for text in [
            "svi:7/6", "svi:6", "svi", "sc:9", "midpoint", "verlet", "dop853", "dopri5", "radau5",
            "molly",
        ] {
            assert_eq!(text.parse::<BenchMethod>().unwrap().to_string(), text);
        }
        // A library method's spelling errors are the registry's, naming the text.
        for bad in ["svi:x", "sc:", "svi:6/", "midpoint:3"] {
            let error = bad.parse::<BenchMethod>().unwrap_err();
            assert!(
                matches!(&error, SceneError::Svi(svi::Error::InvalidParameter { name, .. }) if name == "method"),
                "{bad}: {error}"
            );
            assert!(error.to_string().contains(bad), "{error}");
        }
        // Unknown names list the registry and the peers.
        for bad in ["rk45", "dop853:3", ""] {
            let error = bad.parse::<BenchMethod>().unwrap_err();
            assert!(
                matches!(&error, SceneError::BenchMethod { text } if text == bad),
                "{bad}: {error}"
            );
            assert!(
                error
                    .to_string()
                    .contains("verlet, yoshida4, kahan-li6, kahan-li8, trapezoid"),
                "{error}"
            );
            assert!(
                error.to_string().contains("dop853, dopri5, radau5"),
                "{error}"
            );
        }
        assert_eq!(parse_methods(DEFAULT_METHODS).unwrap().len(), 9);
        // The adaptive modes of a library method, and what is not one.
        for text in [
            "svi:9/8@sundman:1",
            "svi:7/6@step",
            "svi:2/1@sem",
            "verlet@sundman:1.5",
        ] {
            assert_eq!(text.parse::<BenchMethod>().unwrap().to_string(), text);
        }
        for peer in [
            "dop853@step",
            "radau5@step",
            "radau5:3",
            "molly:3",
            "molly@step",
        ] {
            assert!(
                matches!(
                    peer.parse::<BenchMethod>(),
                    Err(SceneError::BenchMethod { .. })
                ),
                "{peer}"
            );
        }
        assert!(matches!(
            "svi@r^2".parse::<BenchMethod>(),
            Err(SceneError::Svi(svi::Error::InvalidParameter { name, .. })) if name == "monitor"
        ));
        assert_eq!(
            parse_methods("svi:7/6, sc:9,,dop853, radau5").unwrap(),
            [
                BenchMethod::Library("svi:7/6".parse().unwrap()),
                BenchMethod::Library("sc:9".parse().unwrap()),
                BenchMethod::Dop853,
                BenchMethod::Radau5
            ]
        );
    }
}
