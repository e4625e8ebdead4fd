//! Nonlinear iterations shared by the implicit spectral methods.
//!
//! Like Hairer's GNI codes, every iteration starts from extrapolated stage values and runs to
//! round-off.
//! - [`Newton`] with [`Jacobian::Exact`] (the Jacobian assembled and factorised at every
//!   iteration) stops once an increment is below `1e-10` of the unknowns' size (the next
//!   increment would be at round-off), or when the increments stop decreasing at a level
//!   where only round-off remains.
//! - [`Newton`] with [`Jacobian::Kept`] is the simplified Newton method (Hairer & Wanner,
//!   *Solving ODEs II*, §IV.8): the factorised Jacobian is kept across iterations and across
//!   solves, so the iteration converges linearly, with the observed contraction rate
//!   θ_k = ‖Δ_k‖/‖Δ_{k−1}‖. It is refactorised at the current iterate once θ_k exceeds
//!   [`REFACTOR_CONTRACTION`] (or the increments stop decreasing), after a failure and
//!   whenever the caller [`Newton::invalidate`]s it (a new step size). A linear iteration
//!   is stopped only when its next increment is predicted below one ulp of the unknowns
//!   (θ_k ‖Δ_k‖ ≤ ε ‖z‖) or an increment is at round-off, so that the solution is the one
//!   of the residual to round-off, the same as the exact Newton method's.
//! - [`FixedPoint`] (for non-stiff problems with constant mass matrix, where no Jacobian is
//!   needed) converges linearly, so it stops only when an increment is below two ulps of the
//!   positions it updates, or stops decreasing near round-off. (Iterating further, until the
//!   increment vanishes, bought no accuracy on Kepler at T = 2000 once the stage tables are
//!   exact, and cost 15% more force evaluations. Stopping one iteration earlier, once the
//!   contraction estimate predicts a next change below two ulps, saves 20% of the
//!   evaluations but the iteration approaches its fixed point from one side: the leftover
//!   bias accumulates into a drift of the energy, and the same Kepler run ends 10⁻⁸ off
//!   instead of 10⁻¹¹.)

use crate::error::StepFailure;
use crate::linalg::DenseLu;
use nalgebra::{DMatrix, DVector};
use std::ops::ControlFlow;

/// Relative increment below which the iteration is converged.
const CONVERGED: f64 = 1e-10;
/// Relative increment below which a non-decreasing Newton increment means round-off.
const STALLED: f64 = 1e-6;
/// Relative increment below which a non-decreasing fixed-point increment means round-off.
const FIXED_POINT_NOISE: f64 = 1e-13;
/// Absolute increment below which a non-decreasing increment means round-off, whatever the
/// unknowns' size: at a state at rest the unknowns vanish (their size is no scale at all),
/// while the residual still carries the round-off of order-one terms (a chain's fixed ends,
/// a potential's constants), so the increments stall near 1e-17 instead of reaching zero.
pub(crate) const ABSOLUTE_NOISE: f64 = 1e-13;

/// Whether a non-decreasing increment `size` (after `previous`) is round-off: below `noise`
/// times the unknowns' size `scale`, or below [`ABSOLUTE_NOISE`].
pub(crate) fn stalled(size: f64, previous: f64, noise: f64, scale: f64) -> bool {
    size >= previous && (size <= noise * scale || size <= ABSOLUTE_NOISE)
}

/// Contraction rate θ above which the simplified Newton method refactorises its Jacobian at
/// the current iterate. Chosen by instruction counts (callgrind) of SVI 4/3 and 7/6 on the
/// double pendulum, h = 0.01 and 0.05, T = 20 (`docs/results/newton.md`, issue #15): summed
/// over the four runs 0.1 cost 364 M instructions, 0.03 and 0.01 302 M each, 0.003 308 M; 0.03
/// factorises half as often as 0.01.
pub(crate) const REFACTOR_CONTRACTION: f64 = 0.03;

/// How a [`Newton`] iteration treats its Jacobian.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Jacobian {
    /// Assembled and factorised at every iteration (Newton's method).
    Exact,
    /// Factorised only when it no longer contracts well, and kept across iterations and
    /// solves (the simplified Newton method).
    Kept,
}

/// Work of one Newton solve.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Solved {
    /// Iterations (residual evaluations and linear solves).
    pub(crate) iterations: usize,
    /// Jacobians assembled and factorised.
    pub(crate) factorizations: usize,
}

/// Buffers of a Newton iteration on `size` unknowns.
#[derive(Debug, Clone)]
pub(crate) struct Newton {
    pub(crate) lu: DenseLu,
    pub(crate) residual: DVector<f64>,
    pub(crate) max_iterations: usize,
    /// Whether `lu` holds factors that [`Jacobian::Kept`] may reuse.
    factored: bool,
    /// Relative size of a non-decreasing [`Jacobian::Kept`] increment that counts as
    /// round-off.
    noise: f64,
    /// Contraction rate above which [`Jacobian::Kept`] refactorises.
    refactor: f64,
    /// Least size of the unknowns that the stopping rules measure increments against.
    scale_floor: f64,
    /// The predicted next [`Jacobian::Kept`] increment, in units of ε times the unknowns,
    /// below which the iteration stops (default 1).
    stop: f64,
}

impl Newton {
    pub(crate) fn new(size: usize, max_iterations: usize) -> Self {
        Newton {
            lu: DenseLu::new(size),
            residual: DVector::zeros(size),
            max_iterations,
            factored: false,
            noise: FIXED_POINT_NOISE,
            refactor: REFACTOR_CONTRACTION,
            scale_floor: 0.0,
            stop: 1.0,
        }
    }

    /// Stop a [`Jacobian::Kept`] iteration once its predicted next increment is below ε/16 of
    /// the unknowns instead of ε: the error left in each step is then round-off, not a
    /// remainder of the iteration that has the same sign step after step and drifts (as
    /// [`FixedPoint::to_noise`]). On the SO(3) scenes (2000 steps) the remainder at ε moved the
    /// final state by 3–6e-13 against Newton's method run to convergence; at ε/4 by up to
    /// 1.6e-13, at ε/16 by 3.3e-14, the size of a 1-ulp change of the initial state; it costs
    /// about 10 % more iterations.
    pub(crate) fn until_noise(mut self) -> Self {
        self.stop = 0.0625;
        self
    }

    /// Measure increments against at least `floor` (default 0: the unknowns' own size), for
    /// unknowns that are offsets of larger quantities and so carry their round-off.
    pub(crate) fn set_scale_floor(&mut self, floor: f64) {
        self.scale_floor = floor;
    }

    /// Refactorise a [`Jacobian::Kept`] iteration only once its contraction rate exceeds
    /// `contraction` (default [`REFACTOR_CONTRACTION`]): for systems whose Jacobian costs many
    /// residuals.
    pub(crate) fn with_refactor(mut self, contraction: f64) -> Self {
        self.refactor = contraction;
        self
    }

    /// Count a non-decreasing [`Jacobian::Kept`] increment below `noise` times the unknowns
    /// as round-off (default `1e-13`), for ill-conditioned systems whose solution is known
    /// only to that level.
    pub(crate) fn with_noise(mut self, noise: f64) -> Self {
        self.noise = noise;
        self
    }

    /// Drop the kept factors: the next [`Jacobian::Kept`] iteration refactorises.
    pub(crate) fn invalidate(&mut self) {
        self.factored = false;
    }

    /// Solve F(z) = 0 starting from `z` by Newton's method with the exact Jacobian.
    /// `assemble(z, jacobian, residual)` writes F(z) and F'(z). Returns the number of
    /// iterations.
    pub(crate) fn solve<F>(
        &mut self,
        z: &mut DVector<f64>,
        mut assemble: F,
    ) -> Result<usize, StepFailure>
    where
        F: FnMut(&DVector<f64>, &mut DMatrix<f64>, &mut DVector<f64>),
    {
        let solved = self.iterate(z, Jacobian::Exact, |z, jacobian, residual| {
            // `Exact` asks for the Jacobian at every iteration.
            if let Some(jacobian) = jacobian {
                assemble(z, jacobian, residual);
            }
        })?;
        Ok(solved.iterations)
    }

    /// Solve F(z) = 0 starting from `z`. `assemble(z, jacobian, residual)` writes F(z), and
    /// F'(z) when `jacobian` is `Some` (always with [`Jacobian::Exact`], only when the
    /// factors are refreshed with [`Jacobian::Kept`]).
    pub(crate) fn iterate<F>(
        &mut self,
        z: &mut DVector<f64>,
        jacobian: Jacobian,
        mut assemble: F,
    ) -> Result<Solved, StepFailure>
    where
        F: FnMut(&DVector<f64>, Option<&mut DMatrix<f64>>, &mut DVector<f64>),
    {
        let result = self.iterate_unguarded(z, jacobian, &mut assemble);
        if result.is_err() {
            self.factored = false;
        }
        result
    }

    fn iterate_unguarded<F>(
        &mut self,
        z: &mut DVector<f64>,
        jacobian: Jacobian,
        assemble: &mut F,
    ) -> Result<Solved, StepFailure>
    where
        F: FnMut(&DVector<f64>, Option<&mut DMatrix<f64>>, &mut DVector<f64>),
    {
        let mut previous = f64::INFINITY;
        let mut factorizations = 0;
        for iteration in 1..=self.max_iterations {
            let refactor = jacobian == Jacobian::Exact || !self.factored;
            if refactor {
                self.factored = false;
                assemble(z, Some(self.lu.matrix_mut()), &mut self.residual);
            } else {
                assemble(z, None, &mut self.residual);
            }
            if !self.residual.iter().all(|r| r.is_finite()) {
                return Err(StepFailure::NonFinite);
            }
            if refactor {
                self.lu.factor().map_err(|_| StepFailure::SingularMatrix)?;
                self.factored = true;
                factorizations += 1;
            }
            self.lu.solve_in_place(&mut self.residual);
            *z -= &self.residual;
            let size = self.residual.amax();
            if !size.is_finite() {
                return Err(StepFailure::NonFinite);
            }
            let scale = z.amax().max(self.scale_floor);
            let converged = match jacobian {
                Jacobian::Exact => {
                    size <= CONVERGED * scale || stalled(size, previous, STALLED, scale)
                }
                // θ ‖Δ‖ predicts the next increment (θ is unknown at the first iteration).
                Jacobian::Kept => {
                    size <= 2.0 * f64::EPSILON * scale
                        || (previous.is_finite()
                            && size * size <= self.stop * f64::EPSILON * scale * previous)
                        || stalled(size, previous, self.noise, scale)
                }
            };
            if converged || size == 0.0 {
                return Ok(Solved {
                    iterations: iteration,
                    factorizations,
                });
            }
            if !refactor && size > self.refactor * previous {
                self.factored = false;
            }
            previous = size;
        }
        Err(StepFailure::NonConvergence {
            iterations: self.max_iterations,
            residual: previous,
        })
    }
}

/// Convergence control of a fixed-point iteration run to round-off.
#[derive(Debug, Clone, Copy)]
pub(crate) struct FixedPoint {
    previous: f64,
    iterations: usize,
    max_iterations: usize,
    /// Whether the iteration runs to its noise (`FixedPoint::to_noise`).
    to_noise: bool,
    /// Whether the iteration stops on its predicted error (`FixedPoint::predicting`).
    predicting: bool,
}

impl FixedPoint {
    /// Converged at an increment within 2ε of the unknowns' size, or once the increments
    /// stall at round-off.
    pub(crate) fn new(max_iterations: usize) -> Self {
        FixedPoint {
            previous: f64::INFINITY,
            iterations: 0,
            max_iterations,
            to_noise: false,
            predicting: false,
        }
    }

    /// Converged, as [`FixedPoint::new`], at an increment within 2ε of the unknowns' size, or
    /// once the error the contraction predicts for the current iterate, ρ/(1 − ρ) times the
    /// increment with ρ the ratio of the last two increments, is: one iteration fewer than
    /// waiting for the increment itself, for linear iterations (whose ratio is the
    /// contraction's) whose error may follow the starting values from step to step (the
    /// adjoint's transposed stage equations: their error feeds a gradient, not a
    /// trajectory's energy).
    pub(crate) fn predicting(max_iterations: usize) -> Self {
        FixedPoint {
            predicting: true,
            ..FixedPoint::new(max_iterations)
        }
    }

    /// Converged once an increment falls below ε/4 of the unknowns' size (their changes are
    /// then below half an ulp: round-off) or the increments stop decreasing: the iterate is
    /// then a fixed point to within the noise of its own evaluation, whose error is
    /// uncorrelated from step to step. Stopping at 2ε instead leaves an error that follows the
    /// smooth error of the starting values, the same sign step after step: on Kepler (SVI
    /// 13/12, 1.4·10⁶ steps) the energy error then drifted linearly to 2e-12 (7e-13 at ε), and
    /// random-walked to 5e-14 at ε/4 (3e-14 run until stalled, a fifth of an iteration a step
    /// more).
    pub(crate) fn to_noise(max_iterations: usize) -> Self {
        FixedPoint {
            to_noise: true,
            ..FixedPoint::new(max_iterations)
        }
    }

    /// Iterations performed so far.
    pub(crate) fn iterations(&self) -> usize {
        self.iterations
    }

    /// Record an increment of infinity norm `size`, for unknowns whose round-off level is
    /// `scale` times the machine epsilon (the size of the positions they build); `Ok(true)`
    /// once converged.
    pub(crate) fn converged(&mut self, size: f64, scale: f64) -> Result<bool, StepFailure> {
        self.iterations += 1;
        if !size.is_finite() {
            return Err(StepFailure::NonFinite);
        }
        let threshold = if self.to_noise { 0.25 } else { 2.0 } * f64::EPSILON * scale;
        // (The first increment has no ratio: `previous` is infinite.)
        let rate = size / self.previous;
        if size <= threshold
            || (self.predicting
                && self.previous.is_finite()
                && rate < 0.5
                && size * rate <= threshold * (1.0 - rate))
            || stalled(size, self.previous, FIXED_POINT_NOISE, scale)
        {
            return Ok(true);
        }
        if self.iterations >= self.max_iterations {
            return Err(StepFailure::NonConvergence {
                iterations: self.iterations,
                residual: size,
            });
        }
        self.previous = size;
        Ok(false)
    }
}

/// What a step does after trying the fixed-point iteration: `Break` with the step's result,
/// or `Continue` with the iterations spent, to go on with Newton's method for this step.
///
/// A fixed point that reaches its cap or diverges hands the step to Newton's method (from the
/// same starting values), for every model: near a close approach the contraction factor
/// h²‖M⁻¹∂f/∂q‖ approaches 1, and the fixed point may still be creeping at the cap (Kepler
/// e = 0.9, h = 0.2: increments of 3e-15 after 50 iterations, not yet stalled), where Newton
/// converges in a few iterations. A velocity-dependent force makes the fixed point contract
/// only by a factor O(h ‖M⁻¹ ∂f_L/∂q̇‖), which does not improve along the run, so for a
/// forced model the switch is for the rest of the run (`newton_only`).
pub(crate) fn after_fixed_point<T>(
    result: Result<T, StepFailure>,
    forced: bool,
    newton_only: &mut bool,
) -> ControlFlow<Result<T, StepFailure>, usize> {
    let spent = match result {
        Err(StepFailure::NonConvergence { iterations, .. }) => iterations,
        Err(StepFailure::NonFinite) => 0,
        result => return ControlFlow::Break(result),
    };
    *newton_only |= forced;
    ControlFlow::Continue(spent)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// F(x) = x ∘ x − 2 (componentwise) and its diagonal Jacobian 2 diag(x).
    fn square_minus_two(
        x: &DVector<f64>,
        jacobian: &mut DMatrix<f64>,
        residual: &mut DVector<f64>,
    ) {
        jacobian.fill(0.0);
        for i in 0..x.len() {
            residual[i] = x[i] * x[i] - 2.0;
            jacobian[(i, i)] = 2.0 * x[i];
        }
    }

    #[test]
    fn newton_converges_quadratically_to_square_root_of_two_in_five_iterations() {
        // Reference: the root √2 and Newton's iterates from 1 (or 2, whose first iterate is
        // also 3/2): 3/2, 17/12, 577/408, ... (the Babylonian method), with errors
        // e_{k+1} = e_k² / (2 x_k) → e_k² / (2√2). The fifth increment, 1.6e-12, is the
        // first below 1e-10 · √2.
        let mut newton = Newton::new(3, 20);
        let mut z = DVector::from_vec(vec![1.0, 1.5, 2.0]);
        let mut errors = Vec::new();
        let iterations = newton
            .solve(&mut z, |x, jacobian, residual| {
                errors.push((x[0] - std::f64::consts::SQRT_2).abs());
                square_minus_two(x, jacobian, residual);
            })
            .unwrap();
        assert_eq!(iterations, 5);
        for x in z.iter() {
            assert!((x - std::f64::consts::SQRT_2).abs() <= f64::EPSILON, "{x}");
        }
        // e_{k+1}/e_k² tends to 1/(2√2) = 0.354 (0.5 and 0.333 on the first two iterates).
        let ratios: Vec<f64> = errors
            .windows(2)
            .filter(|pair| pair[0] > 1e-7)
            .map(|pair| pair[1] / (pair[0] * pair[0]))
            .collect();
        assert_eq!(ratios.len(), 4, "{errors:?}");
        for ratio in &ratios {
            assert!((0.3..=0.5).contains(ratio), "{ratios:?}");
        }
        assert!((ratios[3] - 0.25 * std::f64::consts::SQRT_2).abs() < 1e-3);
    }

    #[test]
    fn newton_capped_returns_non_convergence_with_iterations_and_last_increment() {
        // From 1 the increments are 1/2, 1/12 and 17/12 − 577/408 = 1/408.
        let mut newton = Newton::new(2, 3);
        let mut z = DVector::from_vec(vec![1.0, 1.0]);
        let result = newton.solve(&mut z, square_minus_two);
        let Err(StepFailure::NonConvergence {
            iterations,
            residual,
        }) = result
        else {
            panic!("expected NonConvergence, got {result:?}");
        };
        assert_eq!(iterations, 3);
        assert!((residual - 1.0 / 408.0).abs() < 1e-15, "{residual}");
        assert!((z[0] - 577.0 / 408.0).abs() < 1e-15);
    }

    #[test]
    fn increments_stalled_at_round_off_of_a_vanishing_solution_converge() {
        // F(z) = z − δ_k with δ_k = ±1e-17 alternating: the solution is 0 up to a residual
        // round-off of 1e-17 (a state at rest whose equations carry order-one terms). The
        // increments stall at 2e-17 while z itself is 1e-17: no relative test passes, and
        // before the absolute floor every such solve ended in NonConvergence.
        let mut k = 0;
        let mut rest =
            |z: &DVector<f64>, jacobian: &mut DMatrix<f64>, residual: &mut DVector<f64>| {
                k += 1;
                let noise = if k % 2 == 0 { 1e-17 } else { -1e-17 };
                jacobian.fill_with_identity();
                residual[0] = z[0] - noise;
            };
        let mut newton = Newton::new(1, 50);
        let mut z = DVector::from_vec(vec![0.0]);
        let iterations = newton.solve(&mut z, &mut rest).unwrap();
        assert!(iterations <= 3, "{iterations}");
        assert!(z[0].abs() <= 1e-17);
        // The fixed point's control alike.
        let mut control = FixedPoint::new(50);
        assert_eq!(control.converged(2e-17, 1e-17), Ok(false));
        assert_eq!(control.converged(2e-17, 1e-17), Ok(true));
        // Run to noise, an increment of ε at size 1 is not yet converged; ε/8 is.
        let mut control = FixedPoint::to_noise(50);
        assert_eq!(control.converged(f64::EPSILON, 1.0), Ok(false));
        assert_eq!(control.converged(f64::EPSILON / 8.0, 1.0), Ok(true));
        assert_eq!(FixedPoint::new(50).converged(f64::EPSILON, 1.0), Ok(true));
        // Predicting: after increments 1e-6 and 1e-11 (ratio 1e-5) the iterate's error is
        // about 1e-16, within 2ε of size 1: converged an iteration before the increment itself
        // falls that low; the first increment alone, with no ratio, never predicts.
        let mut control = FixedPoint::predicting(50);
        assert_eq!(control.converged(1e-6, 1.0), Ok(false));
        assert_eq!(control.converged(1e-11, 1.0), Ok(true));
        let mut plain = FixedPoint::new(50);
        assert_eq!(plain.converged(1e-6, 1.0), Ok(false));
        assert_eq!(plain.converged(1e-11, 1.0), Ok(false));
        assert_eq!(FixedPoint::predicting(50).converged(1e-300, 1.0), Ok(true));
        let mut slow = FixedPoint::predicting(50);
        assert_eq!(slow.converged(1e-9, 1.0), Ok(false));
        // Ratio 0.6: no prediction trusted however small the increment's product.
        assert_eq!(slow.converged(6e-10, 1.0), Ok(false));
        // A stalled increment above the floor in a problem of size 1e-17 is no convergence.
        let mut control = FixedPoint::new(2);
        assert_eq!(control.converged(2e-12, 1e-17), Ok(false));
        assert!(control.converged(2e-12, 1e-17).is_err());
    }

    #[test]
    fn newton_on_a_singular_jacobian_is_a_singular_matrix_failure() {
        // F'(0) = 0: the first Newton matrix is singular.
        let mut newton = Newton::new(2, 10);
        let mut z = DVector::from_vec(vec![0.0, 1.0]);
        assert_eq!(
            newton.solve(&mut z, square_minus_two),
            Err(StepFailure::SingularMatrix)
        );
    }

    #[test]
    fn newton_on_a_nan_residual_is_a_non_finite_failure() {
        let mut newton = Newton::new(2, 10);
        let mut z = DVector::from_vec(vec![1.0, 1.0]);
        let result = newton.solve(&mut z, |x, jacobian, residual| {
            square_minus_two(x, jacobian, residual);
            residual[1] = f64::NAN;
        });
        assert_eq!(result, Err(StepFailure::NonFinite));
        // A finite residual whose increment overflows (1e300 / 1e-300) is caught as well.
        let mut newton = Newton::new(1, 10);
        let mut z = DVector::from_vec(vec![1.0]);
        let result = newton.solve(&mut z, |_, jacobian, residual| {
            jacobian[(0, 0)] = 1e-300;
            residual[0] = 1e300;
        });
        assert_eq!(result, Err(StepFailure::NonFinite));
    }

    /// F(x) = x ∘ x − a with the Jacobian 2 diag(x) only when asked for.
    fn square_minus(
        a: f64,
    ) -> impl FnMut(&DVector<f64>, Option<&mut DMatrix<f64>>, &mut DVector<f64>) {
        move |x, jacobian, residual| {
            for i in 0..x.len() {
                residual[i] = x[i] * x[i] - a;
            }
            if let Some(jacobian) = jacobian {
                jacobian.fill(0.0);
                for i in 0..x.len() {
                    jacobian[(i, i)] = 2.0 * x[i];
                }
            }
        }
    }

    #[test]
    fn simplified_newton_reaches_the_root_to_round_off_and_keeps_its_factors() {
        // Reference: √2 (correctly rounded 1.4142135623730951) and √2.0001. The map
        // x ← x − (x² − 2)/(2 x_J) contracts by |1 − √2/x_J|. From 1 (x_J = 1) the iterates
        // are 3/2, 11/8; the contraction 0.41 > REFACTOR_CONTRACTION refactorises at 11/8,
        // whose rate |1 − √2/(11/8)| = 0.0285 is kept: from x₃ − √2 = 5e-4 about eight more
        // iterations to round-off.
        let mut newton = Newton::new(1, 50);
        let mut z = DVector::from_vec(vec![1.0]);
        let solved = newton
            .iterate(&mut z, Jacobian::Kept, square_minus(2.0))
            .unwrap();
        assert!(
            (z[0] - std::f64::consts::SQRT_2).abs() <= f64::EPSILON,
            "{z}"
        );
        assert_eq!(solved.factorizations, 2, "{solved:?}");
        assert!((10..=12).contains(&solved.iterations), "{solved:?}");
        // A nearby problem reuses the factors at 11/8: the contraction rate is
        // |1 − √2.0001/(11/8)| = 0.0285 < REFACTOR_CONTRACTION, so no factorisation, and from
        // x − √2.0001 = 3.5e-5 about nine iterations to round-off.
        let target = 2.0001f64.sqrt();
        let solved = newton
            .iterate(&mut z, Jacobian::Kept, square_minus(2.0001))
            .unwrap();
        assert!((z[0] - target).abs() <= f64::EPSILON, "{z} vs {target}");
        assert_eq!(solved.factorizations, 0, "{solved:?}");
        assert!((8..=11).contains(&solved.iterations), "{solved:?}");
        // Invalidated, it refactorises at once: one factorisation, Newton's iterates.
        newton.invalidate();
        let solved = newton
            .iterate(&mut z, Jacobian::Kept, square_minus(2.0))
            .unwrap();
        assert_eq!(solved.factorizations, 1, "{solved:?}");
        assert!(
            (z[0] - std::f64::consts::SQRT_2).abs() <= f64::EPSILON,
            "{z}"
        );
        // The exact Jacobian factorises at every iteration (five from 1, as above).
        let mut z = DVector::from_vec(vec![1.0]);
        let solved = newton
            .iterate(&mut z, Jacobian::Exact, square_minus(2.0))
            .unwrap();
        assert_eq!((solved.iterations, solved.factorizations), (5, 5));
    }

    #[test]
    fn a_failed_simplified_newton_drops_its_factors() {
        let mut newton = Newton::new(1, 3);
        let mut z = DVector::from_vec(vec![1.0]);
        assert!(matches!(
            newton.iterate(&mut z, Jacobian::Kept, square_minus(2.0)),
            Err(StepFailure::NonConvergence { iterations: 3, .. })
        ));
        // The next solve starts with a factorisation (of 2x at x = √2 + O(1e-3)).
        newton.max_iterations = 50;
        let solved = newton
            .iterate(&mut z, Jacobian::Kept, square_minus(2.0))
            .unwrap();
        assert!(solved.factorizations >= 1, "{solved:?}");
        assert!(
            (z[0] - std::f64::consts::SQRT_2).abs() <= f64::EPSILON,
            "{z}"
        );
    }

    /// Runs x ← cos x from 1 under a [`FixedPoint`] control with cap `max_iterations`;
    /// returns the last iterate and the control's verdict.
    fn cosine_fixed_point(max_iterations: usize) -> (f64, Result<usize, StepFailure>) {
        let mut control = FixedPoint::new(max_iterations);
        let mut x: f64 = 1.0;
        loop {
            let next = x.cos();
            let change = (next - x).abs();
            x = next;
            match control.converged(change, x.abs()) {
                Ok(true) => return (x, Ok(control.iterations())),
                Ok(false) => {}
                Err(failure) => return (x, Err(failure)),
            }
        }
    }

    #[test]
    fn fixed_point_stops_at_round_off_on_the_dottie_number() {
        // Reference: the fixed point of cos, 0.73908513321516064166 (the Dottie number),
        // correctly rounded 0.7390851332151607. The contraction factor is sin x* = 0.674, so
        // reaching an increment of 2 ulps from |x0 − x*| = 0.26 takes about
        // ln(3e-16 / 0.26) / ln 0.674 ≈ 87 iterations (91 observed).
        let (x, iterations) = cosine_fixed_point(500);
        let iterations = iterations.unwrap();
        assert!((x - 0.7390851332151607).abs() <= 2.0 * f64::EPSILON, "{x}");
        assert!((70..=100).contains(&iterations), "{iterations} iterations");
    }

    #[test]
    fn fixed_point_capped_returns_non_convergence_with_the_cap() {
        let (_, result) = cosine_fixed_point(10);
        let Err(StepFailure::NonConvergence {
            iterations,
            residual,
        }) = result
        else {
            panic!("expected NonConvergence, got {result:?}");
        };
        assert_eq!(iterations, 10);
        // The reported residual is the last increment, |x₁₀ − x₉| of x ← cos x from x₀ = 1.
        let iterates: Vec<f64> = std::iter::successors(Some(1.0f64), |x| Some(x.cos()))
            .take(11)
            .collect();
        assert_eq!(residual, (iterates[10] - iterates[9]).abs());
    }

    #[test]
    fn fixed_point_with_a_nan_increment_is_a_non_finite_failure() {
        let mut control = FixedPoint::new(10);
        assert_eq!(control.converged(0.5, 1.0), Ok(false));
        assert_eq!(
            control.converged(f64::NAN, 1.0),
            Err(StepFailure::NonFinite)
        );
        assert_eq!(control.iterations(), 2);
    }

    #[test]
    fn a_failed_fixed_point_hands_the_step_to_newton_and_forced_models_for_good() {
        let capped = StepFailure::NonConvergence {
            iterations: 7,
            residual: 0.1,
        };
        // Forced: a capped or diverging fixed point hands over to Newton for the rest of
        // the run.
        let mut newton_only = false;
        let flow = after_fixed_point::<()>(Err(capped), true, &mut newton_only);
        assert_eq!(flow, ControlFlow::Continue(7));
        assert!(newton_only);
        let mut newton_only = false;
        let flow = after_fixed_point::<()>(Err(StepFailure::NonFinite), true, &mut newton_only);
        assert_eq!(flow, ControlFlow::Continue(0));
        assert!(newton_only);
        // Forced, but success or another failure ends the step.
        let mut newton_only = false;
        let flow = after_fixed_point(Ok(3), true, &mut newton_only);
        assert_eq!(flow, ControlFlow::Break(Ok(3)));
        let flow =
            after_fixed_point::<()>(Err(StepFailure::SingularMatrix), true, &mut newton_only);
        assert_eq!(flow, ControlFlow::Break(Err(StepFailure::SingularMatrix)));
        assert!(!newton_only);
        // Unforced: a capped or diverging fixed point hands this step to Newton, and the
        // next step tries the fixed point again.
        for (failure, spent) in [(capped, 7), (StepFailure::NonFinite, 0)] {
            let mut newton_only = false;
            let flow = after_fixed_point::<()>(Err(failure), false, &mut newton_only);
            assert_eq!(flow, ControlFlow::Continue(spent));
            assert!(!newton_only);
        }
    }
}
