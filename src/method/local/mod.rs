//! Methods on runtime-sized ℝⁿ for Lagrangians written as sums of local terms
//! ([`LocalLagrangian`]): chains, lattices, discretised strings and fields, up to 10⁵
//! degrees of freedom and beyond.
//!
//! A method here is the same options struct as on ℝᴺ ([`crate::Svi`], [`crate::StormerVerlet`])
//! with a second implementation, of [`LocalMethod`], whose data layout is made for large n:
//! stage values as runtime vectors, derivatives of L assembled term by term in O(n)
//! ([`crate::model::local::LocalLagrangianExt`]), no dense n × n matrix anywhere. Every
//! [`LocalMethod`] is a [`Step`] on [`DynEuclidean`] by the blanket implementation below, so it
//! runs through the one stepping loop ([`crate::Integrator`]) with observers, recovery, the
//! divergence limit and output times like every other method.
//!
//! What runs on large systems: Störmer–Verlet ([`verlet`], explicit kick–drift–kick for a
//! constant mass matrix) and its compositions of orders 4, 6 and 8 ([`composition`]), SVI by
//! the Hessian-free fixed point for a constant mass matrix and by sparse Newton for every
//! other Lagrangian ([`svi`], with the sparse Newton of
//! `crate::method::variational::stage_newton`; the linear solves go through the seam of
//! [`crate::linalg::sparse`]). Spectral collocation, the implicit classic variational
//! integrators, linear stability analysis and the tangent map stay on fixed-size ℝᴺ (small
//! systems) for now; asking for them on a runtime-dimension model is an error that says so.

pub mod composition;
pub mod svi;

pub mod verlet;

use crate::error::{Error, StepFailure, require_finite_entries};
use crate::method::space::{DynEuclidean, DynInitial, DynPoint, DynState};
use crate::method::step::{Hermite, Step};
use crate::method::{MethodInfo, StepReport};
use crate::model::Structure;
use crate::model::legendre;
use crate::model::local::{LocalLagrangian, LocalLagrangianExt};
use nalgebra::{DVector, Dyn};

/// An integration method for [`LocalLagrangian`] models on runtime-sized ℝⁿ, in the
/// coordinates (q, p).
pub trait LocalMethod {
    /// Buffers and precomputed tables of one run, sized once.
    type Workspace;

    /// Name, order and geometric properties.
    fn info(&self) -> MethodInfo;

    /// Validate the options against the model and build every buffer for steps of size `h`.
    fn local_workspace<L: LocalLagrangian>(
        &self,
        model: &L,
        h: f64,
    ) -> Result<Self::Workspace, Error>;

    /// Advance `state` from `t` to `t + h`, writing the increment into `increment`.
    /// Allocates nothing.
    fn local_step<L: LocalLagrangian>(
        &self,
        model: &L,
        workspace: &mut Self::Workspace,
        t: f64,
        h: f64,
        state: &DynState,
        increment: &mut DynState,
    ) -> Result<StepReport, StepFailure>;

    /// Drop warm-start data (the next step does not continue the last one).
    fn local_restart(&self, workspace: &mut Self::Workspace) {
        let _ = workspace;
    }

    /// The velocity q̇ of the momentum `p` at (t, q), written into `v`, from what the run's
    /// workspace holds (a constant mass matrix's cached inverse, or the sparse inverse
    /// Legendre map started at `v`'s value on entry).
    fn local_velocity<L: LocalLagrangian>(
        &self,
        model: &L,
        workspace: &Self::Workspace,
        t: f64,
        q: &DVector<f64>,
        p: &DVector<f64>,
        v: &mut DVector<f64>,
    ) -> Result<(), Error>;
}

/// M⁻¹ of a constant mass matrix on runtime-sized ℝⁿ (diagonal or sparse LU, from the terms'
/// blocks).
pub(crate) type MassInverse = crate::model::mass_inverse::MassInverse<Dyn>;

/// M⁻¹ of `model`'s mass matrix at (t, q) (q̇ = 0), from its terms' blocks.
fn mass_inverse<L: LocalLagrangian>(
    model: &L,
    t: f64,
    q: &DVector<f64>,
) -> Result<MassInverse, Error> {
    MassInverse::of_terms(model, t, q, &DVector::zeros(q.len()))
}

/// The velocity q̇ of the momentum `p` at (t, q) without a run's workspace, written into
/// `v`: M⁻¹p for a constant mass matrix, else the inverse Legendre map by sparse Newton
/// from `v`'s value on entry.
pub(crate) fn cold_velocity<L: LocalLagrangian>(
    model: &L,
    t: f64,
    q: &DVector<f64>,
    p: &DVector<f64>,
    v: &mut DVector<f64>,
) -> Result<(), Error> {
    if L::STRUCTURE == Structure::ConstantMass {
        mass_inverse(model, t, q)?.apply_into(p, v);
        return Ok(());
    }
    legendre::velocity(model, t, q.as_slice(), p.as_slice(), v.as_mut_slice())
}

/// The constant mass matrix of `model` at (t, q), inverted, after checking that the model
/// declares [`Structure::ConstantMass`] (the only structure the large-system methods take
/// so far).
pub(crate) fn constant_mass<L: LocalLagrangian>(
    model: &L,
    method: &'static str,
    t: f64,
    q: &DVector<f64>,
) -> Result<MassInverse, Error> {
    if L::STRUCTURE != Structure::ConstantMass {
        return Err(Error::invalid(
            "structure",
            format!(
                "{method} on a runtime-dimension model needs a constant mass matrix \
                 (Structure::ConstantMass); a general Lagrangian takes svi (sparse Newton)"
            ),
        ));
    }
    mass_inverse(model, t, q)
}

impl<L: LocalLagrangian, M: LocalMethod> Step<L, DynEuclidean> for M {
    type Workspace = M::Workspace;

    fn info(&self) -> MethodInfo {
        LocalMethod::info(self)
    }

    fn workspace(&self, model: &L, h: f64) -> Result<M::Workspace, Error> {
        model.check_indices()?;
        self.local_workspace(model, h)
    }

    fn step(
        &self,
        model: &L,
        workspace: &mut M::Workspace,
        t: f64,
        h: f64,
        state: &DynState,
        increment: &mut DynState,
    ) -> Result<StepReport, StepFailure> {
        self.local_step(model, workspace, t, h, state, increment)
    }

    fn restart(&self, workspace: &mut M::Workspace) {
        self.local_restart(workspace);
    }

    fn tangent_map(
        &self,
        _model: &L,
        _workspace: &mut M::Workspace,
        _t: f64,
        _h: f64,
        _state: &DynState,
    ) -> Result<(DynState, nalgebra::DMatrix<f64>), StepFailure> {
        Err(StepFailure::Unsupported {
            option: "tangent_map",
            reason: "the tangent map of a runtime-dimension model (a dense 2n × 2n matrix) is \
                     not available yet",
        })
    }

    fn initial_state(&self, model: &L, t0: f64, initial: &DynInitial) -> Result<DynState, Error> {
        let n = model.dimension();
        let (q, second, name) = match initial {
            DynInitial::Velocity { q, v } => (q, v, "initial velocity"),
            DynInitial::Momentum { q, p } => (q, p, "initial momentum"),
        };
        for (what, x) in [("initial position", q), (name, second)] {
            if x.len() != n {
                return Err(Error::invalid(
                    what,
                    format!("has {} components, the model has {n} coordinates", x.len()),
                ));
            }
            require_finite_entries(what, x)?;
        }
        let y = match initial {
            DynInitial::Momentum { p, .. } => p.clone(),
            DynInitial::Velocity { q, v } => {
                let mut p = DVector::zeros(n);
                model.momentum_into(t0, q, v, &mut p);
                p
            }
        };
        let state = DynState { q: q.clone(), y };
        if !crate::method::StepState::is_finite(&state) {
            return Err(Error::NonFinite {
                what: "momentum ∂L/∂q̇ of the model from the given initial state".into(),
                step: 0,
                t: t0,
            });
        }
        Ok(state)
    }

    /// A [`Structure::ConstantMass`] declaration: ∂L/∂q̇ = M q̇ with the M of the mass
    /// triplets, checked at q̇ = 0 (no linear term) and at the state's velocity.
    fn check_model(&self, model: &L, t: f64, state: &DynState) -> Result<(), Error> {
        if L::STRUCTURE != Structure::ConstantMass {
            return Ok(());
        }
        let n = state.q.len();
        let zero = DVector::zeros(n);
        let mass = mass_inverse(model, t, &state.q)?;
        let v = mass.apply(&state.y);
        let mut p = DVector::zeros(n);
        model.momentum_into(t, &state.q, &v, &mut p);
        let mut linear = DVector::zeros(n);
        model.momentum_into(t, &state.q, &zero, &mut linear);
        let scale = 1.0 + state.y.amax();
        let mismatch = (&p - &state.y).amax();
        if mismatch > 1e-12 * scale || linear.amax() > 1e-12 * scale {
            return Err(Error::invalid(
                "structure",
                format!(
                    "the model declares a constant mass matrix (L = ½ q̇ᵀMq̇ − V), but ∂L/∂q̇ \
                     differs from M q̇ by {mismatch:e} and is {:e} at q̇ = 0",
                    linear.amax()
                ),
            ));
        }
        Ok(())
    }

    fn complete(
        &self,
        model: &L,
        workspace: Option<&M::Workspace>,
        t: f64,
        state: &DynState,
        guess: &DVector<f64>,
    ) -> Result<DynPoint, Error> {
        let mut point = <Self as Step<L, DynEuclidean>>::incomplete(self, t, state, guess);
        self.complete_into(model, workspace, t, state, guess, &mut point)?;
        Ok(point)
    }

    fn complete_into(
        &self,
        model: &L,
        workspace: Option<&M::Workspace>,
        t: f64,
        state: &DynState,
        guess: &DVector<f64>,
        point: &mut DynPoint,
    ) -> Result<(), Error> {
        point.t = t;
        point.q.copy_from(&state.q);
        point.p.copy_from(&state.y);
        point.v.copy_from(guess);
        match workspace {
            Some(workspace) => {
                self.local_velocity(model, workspace, t, &state.q, &state.y, &mut point.v)
            }
            None => cold_velocity(model, t, &state.q, &state.y, &mut point.v),
        }
    }

    fn incomplete(&self, t: f64, state: &DynState, guess: &DVector<f64>) -> DynPoint {
        DynPoint {
            t,
            q: state.q.clone(),
            v: guess.clone(),
            p: state.y.clone(),
        }
    }

    fn point_is_finite(&self, point: &DynPoint) -> bool {
        point.v.iter().chain(point.p.iter()).all(|x| x.is_finite())
    }

    /// Cubic Hermite interpolation of (q, q̇) between the ends of one step, with p from
    /// ∂L/∂q̇ (as on fixed-size ℝᴺ): output times inside steps, O(n) each.
    fn interpolate(&self, model: &L, a: &DynPoint, b: &DynPoint, time: f64) -> Option<DynPoint> {
        let Hermite {
            h,
            value: w,
            rate: d,
        } = Hermite::new(a.t, b.t, time);
        let n = a.q.len();
        let mut q = DVector::zeros(n);
        let mut v = DVector::zeros(n);
        for i in 0..n {
            q[i] = a.q[i] * w[0] + a.v[i] * (h * w[1]) + b.q[i] * w[2] + b.v[i] * (h * w[3]);
            v[i] = (a.q[i] * d[0] + b.q[i] * d[2]) / h + a.v[i] * d[1] + b.v[i] * d[3];
        }
        let mut p = DVector::zeros(n);
        model.momentum_into(time, &q, &v, &mut p);
        Some(DynPoint { t: time, q, v, p })
    }
}
