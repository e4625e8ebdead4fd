//! The peers of `svi bench` and `svi stress` on the first-order form of a Lagrangian, with the
//! settings they are compared at: `ode_solvers`' DOP853 and Dopri5 (explicit), and the stiff
//! solver a user would pick, Radau IIA of order 5 (`differential-equations`' `radau5`, after
//! Hairer & Wanner's RADAU5) with the exact Jacobian of the first-order form by automatic
//! differentiation.

use differential_equations::prelude::{IVP, ImplicitRungeKutta, Matrix, ODE};
use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, OMatrix, OVector, U1};
use ode_solvers::{Dop853, Dopri5, OutputType, System};
use svi::{Dimension, LagrangianExt, Structure, linalg::invert_small};
use svi_models::ZooModel;

/// The first-order form q̇ = v, v̇ = q̈(t, q, v) of a Lagrangian, for `ode_solvers` and
/// `differential-equations`, with a fixed-size state of S = 2N components (as a user of these
/// crates would write it: a heap-allocated `DVector` state would cost the peers a factor of
/// several). Built only for models of a fixed dimension N with 2N = S ([`FirstOrder::new`]).
pub(crate) struct FirstOrder<'a, M, N: Dimension, const S: usize>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    model: &'a M,
    /// The dimension N of the model (S = 2N).
    n: N,
    /// M⁻¹ for constant-mass models (q̈ = M⁻¹ ∂L/∂q, one gradient sweep).
    mass_inverse: Option<OMatrix<f64, N, N>>,
}

impl<'a, M: ZooModel<N>, N: Dimension, const S: usize> FirstOrder<'a, M, N, S>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// The first-order form of `model`; a constant-mass model's mass matrix is inverted once,
    /// at (t0, q0, v0). `None` unless q0 has S/2 components (the state y = (q, q̇) is a fixed
    /// array of S numbers).
    pub(crate) fn new(
        model: &'a M,
        t0: f64,
        q0: &OVector<f64, N>,
        v0: &OVector<f64, N>,
    ) -> Option<Self> {
        let n = q0.shape_generic().0;
        if 2 * n.value() != S {
            return None;
        }
        let mass_inverse = match M::STRUCTURE {
            Structure::ConstantMass => invert_small(&model.mass_matrix(t0, q0, v0)),
            Structure::General => None,
        };
        Some(FirstOrder {
            model,
            n,
            mass_inverse,
        })
    }

    /// The configuration q and velocity q̇ of the state y = (q, q̇).
    fn split(&self, y: &[f64]) -> (OVector<f64, N>, OVector<f64, N>) {
        split(self.n, y)
    }
}

impl<M: ZooModel<N>, N: Dimension, const S: usize> FirstOrder<'_, M, N, S>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// (q̇, q̈) at the state y = (q, q̇), written into `dy` (NaN where the mass matrix is
    /// singular).
    fn rates(&self, t: f64, y: &[f64], dy: &mut [f64]) {
        let (q, v) = self.split(y);
        let a = match &self.mass_inverse {
            Some(inverse) => inverse * self.model.force(t, &q, &v),
            None => self
                .model
                .acceleration(t, &q, &v)
                .unwrap_or_else(|| OVector::from_element_generic(self.n, U1, f64::NAN)),
        };
        let n = self.n.value();
        dy[..n].copy_from_slice(v.as_slice());
        dy[n..2 * n].copy_from_slice(a.as_slice());
    }
}

/// The first-order form as the peers see it: its rates and the Jacobian of its rates at a
/// state of `y.len()` numbers.
trait FirstOrderForm {
    /// (q̇, q̈) at y = (q, q̇), into `dy`.
    fn rates(&self, t: f64, y: &[f64], dy: &mut [f64]);
    /// [[0, I], [∂q̈/∂q, ∂q̈/∂q̇]] at y = (q, q̇), into `j`.
    fn jacobian(&self, t: f64, y: &[f64], j: &mut Matrix<f64>);
}

impl<M: ZooModel<N>, N: Dimension, const S: usize> FirstOrderForm for FirstOrder<'_, M, N, S>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    fn rates(&self, t: f64, y: &[f64], dy: &mut [f64]) {
        FirstOrder::rates(self, t, y, dy);
    }

    /// The acceleration's Jacobian by automatic differentiation (NaN where the mass matrix is
    /// singular).
    fn jacobian(&self, t: f64, y: &[f64], j: &mut Matrix<f64>) {
        let (q, v) = self.split(y);
        let derivative = self.model.acceleration_jacobian(t, &q, &v);
        let n = self.n.value();
        for r in 0..n {
            for c in 0..n {
                j[(r, c)] = 0.0;
                j[(r, n + c)] = if r == c { 1.0 } else { 0.0 };
                let (dq, dv) = derivative
                    .as_ref()
                    .map_or((f64::NAN, f64::NAN), |d| (d.q[(r, c)], d.v[(r, c)]));
                j[(n + r, c)] = dq;
                j[(n + r, n + c)] = dv;
            }
        }
    }
}

/// A [`FirstOrder`] behind a trait object, the system the peers integrate: each peer is
/// compiled once per state size S, not once per model (a sixteenth of the command line's
/// code), for one indirect call per evaluation of the rates (an automatic-differentiation
/// acceleration each).
#[derive(Clone, Copy)]
pub(crate) struct PeerSystem<'a, const S: usize>(&'a dyn FirstOrderForm);

impl<'a, M: ZooModel<N>, N: Dimension, const S: usize> From<&'a FirstOrder<'a, M, N, S>>
    for PeerSystem<'a, S>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    fn from(system: &'a FirstOrder<'a, M, N, S>) -> Self {
        PeerSystem(system)
    }
}

impl<const S: usize> System<f64, ode_solvers::SVector<f64, S>> for PeerSystem<'_, S> {
    fn system(
        &self,
        t: f64,
        y: &ode_solvers::SVector<f64, S>,
        dy: &mut ode_solvers::SVector<f64, S>,
    ) {
        self.0.rates(t, y.as_slice(), dy.as_mut_slice());
    }
}

impl<const S: usize> ODE<f64, [f64; S]> for PeerSystem<'_, S> {
    fn diff(&self, t: f64, y: &[f64; S], dydt: &mut [f64; S]) {
        self.0.rates(t, y, dydt);
    }

    fn jacobian(&self, t: f64, y: &[f64; S], j: &mut Matrix<f64>) {
        self.0.jacobian(t, y, j);
    }
}

/// The configuration q and velocity q̇ (`n` components each) of a peer's state y = (q, q̇).
pub(crate) fn split<N: Dimension>(n: N, y: &[f64]) -> (OVector<f64, N>, OVector<f64, N>)
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let size = n.value();
    (
        OVector::from_column_slice_generic(n, U1, &y[..size]),
        OVector::from_column_slice_generic(n, U1, &y[size..2 * size]),
    )
}

/// What the peers are wired for, in a message about a model of dimension N that they cannot
/// run (their states are arrays of S = 2N numbers, S a constant): models of a fixed N ≤ 3.
pub(crate) fn wired_for<N: Dimension>() -> &'static str {
    match N::try_to_usize() {
        Some(_) => "models of dimension ≤ 3",
        None => {
            "models of a fixed dimension ≤ 3, not for a model whose number of coordinates is \
             known at run time only"
        }
    }
}

/// The tolerance at and below which `radau5` does not run: the crate, as Hairer & Wanner's
/// RADAU5, rejects rtol ≤ 10·uround with uround = 10⁻¹⁶.
pub const RADAU5_TOLERANCE_FLOOR: f64 = 1e-15;

/// Outcome of one adaptive peer run to the horizon.
pub(crate) struct PeerRun<const S: usize> {
    /// Steps taken, accepted and rejected.
    pub(crate) steps: usize,
    /// Right-hand-side evaluations (a Jacobian's evaluations are not counted).
    pub(crate) evaluations: usize,
    /// Newton iterations (none for the explicit peers).
    pub(crate) iterations: usize,
    /// The states (q, q̇) at the accepted steps, the last one at the horizon (never empty).
    pub(crate) states: Vec<ode_solvers::SVector<f64, S>>,
}

/// `differential-equations`' Radau IIA of order 5 from `t0` to `t_end` with rtol = atol = `tol`
/// (which the crate, as RADAU5, turns into 0.1·tol^(2/3) internally) and the crate's other
/// defaults (its predictive step controller, Newton tolerance and starting step), the exact
/// Jacobian of the first-order form, output at every accepted step and a high step cap (as the
/// `ode_solvers` peers); `None` if it fails (also for `tol` ≤ [`RADAU5_TOLERANCE_FLOOR`]) or
/// stops short.
pub(crate) fn radau5<const S: usize>(
    system: PeerSystem<'_, S>,
    t0: f64,
    t_end: f64,
    y0: [f64; S],
    tol: f64,
) -> Option<PeerRun<S>> {
    let solution = IVP::ode(&system, t0, t_end, y0)
        .method(
            ImplicitRungeKutta::radau5()
                .rtol(tol)
                .atol(tol)
                .max_steps(2_000_000_000),
        )
        .solve()
        .ok()?;
    let reached = *solution.t.last()?;
    if (reached - t_end).abs() > 1e-9 * t_end.abs().max(1.0) {
        return None;
    }
    Some(PeerRun {
        steps: solution.steps.accepted + solution.steps.rejected,
        evaluations: solution.evals.function,
        iterations: solution.evals.newton,
        states: solution.y.into_iter().map(Into::into).collect(),
    })
}

/// A constructor of an `ode_solvers` stepper from `t0` to `t_end` with rtol = atol = `tol`,
/// as the peers run it: the crate's controller defaults (safety, beta, smallest and largest
/// step factor), sparse output (the accepted step points only) and a high step cap (as the
/// kepler-peers tool).
macro_rules! peer {
    ($(#[$doc:meta])* $name:ident, $solver:ident, ($($controller:expr),+)) => {
        $(#[$doc])*
        pub(crate) fn $name<F: System<f64, ode_solvers::SVector<f64, S>>, const S: usize>(
            system: F,
            t0: f64,
            t_end: f64,
            y0: ode_solvers::SVector<f64, S>,
            tol: f64,
        ) -> $solver<f64, ode_solvers::SVector<f64, S>, F> {
            let span = t_end - t0;
            $solver::from_param(
                system,
                t0,
                t_end,
                span,
                y0,
                tol,
                tol,
                $($controller,)+
                span,
                0.0,
                2_000_000_000,
                1000,
                OutputType::Sparse,
            )
        }
    };
}

peer!(
    /// `ode_solvers`' DOP853 (order 8), set up as the peers run it.
    dop853,
    Dop853,
    (0.9, 0.0, 0.333, 6.0)
);

peer!(
    /// `ode_solvers`' Dopri5 (order 5), set up as the peers run it.
    dopri5,
    Dopri5,
    (0.9, 0.04, 0.2, 10.0)
);
