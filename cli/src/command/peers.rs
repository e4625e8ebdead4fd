//! The `ode_solvers` peers of `svi bench` and `svi stress`: DOP853 and Dopri5 on the
//! first-order form of a Lagrangian, with the settings the peers are compared at.

use nalgebra::{SMatrix, SVector};
use ode_solvers::{Dop853, Dopri5, OutputType, System};
use svi::{LagrangianExt, Structure, linalg::invert_small};
use svi_models::ZooModel;

/// The first-order form q̇ = v, v̇ = q̈(t, q, v) of a Lagrangian, for `ode_solvers`, with a
/// fixed-size state of S = 2N components (as a user of `ode_solvers` would write it: a
/// heap-allocated `DVector` state would cost the peers a factor of several).
pub(crate) struct FirstOrder<'a, M, const N: usize, const S: usize> {
    model: &'a M,
    /// M⁻¹ for constant-mass models (q̈ = M⁻¹ ∂L/∂q, one gradient sweep).
    mass_inverse: Option<SMatrix<f64, N, N>>,
}

impl<'a, M: ZooModel<N>, const N: usize, const S: usize> FirstOrder<'a, M, N, S> {
    /// The first-order form of `model`; a constant-mass model's mass matrix is inverted once,
    /// at (t0, q0, v0).
    pub(crate) fn new(model: &'a M, t0: f64, q0: &SVector<f64, N>, v0: &SVector<f64, N>) -> Self {
        let mass_inverse = match M::STRUCTURE {
            Structure::ConstantMass => invert_small(&model.mass_matrix(t0, q0, v0)),
            Structure::General => None,
        };
        FirstOrder {
            model,
            mass_inverse,
        }
    }
}

impl<M: ZooModel<N>, const N: usize, const S: usize> System<f64, ode_solvers::SVector<f64, S>>
    for FirstOrder<'_, M, N, S>
{
    fn system(
        &self,
        t: f64,
        y: &ode_solvers::SVector<f64, S>,
        dy: &mut ode_solvers::SVector<f64, S>,
    ) {
        let q = SVector::<f64, N>::from_fn(|i, _| y[i]);
        let v = SVector::<f64, N>::from_fn(|i, _| y[N + i]);
        let a = match self.mass_inverse {
            Some(inverse) => inverse * self.model.force(t, &q, &v),
            None => self
                .model
                .acceleration(t, &q, &v)
                .unwrap_or_else(|| SVector::repeat(f64::NAN)),
        };
        for i in 0..N {
            dy[i] = v[i];
            dy[N + i] = a[i];
        }
    }
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
