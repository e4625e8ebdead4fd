//! [`LieSvi`] on any Lie group ([`GroupSpace`]): the full form (§5.3) and the reduced
//! Euler–Poincaré form (§5.4) of the parent module, with the group's exp, dexp and Ad in
//! place of SO(3)'s closed forms.
//!
//! The derivation of the parent module holds on every group until its last line, where
//! SO(3)'s dexp_xᵀ = dexp_{−x} was used. In general the step solves
//!
//! 0 = ∂S/∂ξᵛ (ν = 1, …, d − 1),  0 = P − dexp_{ξᵈ}ᵀ (μ_k + g_R),
//!
//! and then, from dexp_x = Ad_{exp x} dexp_{−x},
//!
//! g_{k+1} = g_k F,  μ_{k+1} = Ad_Fᵀ (μ_k + g_R),  F = exp(ξᵈ),
//!
//! the discrete Euler–Poincaré equation μ_{k+1} = Ad*_F(μ_k + g_R) with the left-trivialised
//! discrete momenta. The increments are g_k (F − e) ([`LieGroup::translate_difference`] of
//! [`LieGroup::exp_minus_identity`]) and (Ad_F − I)ᵀμ_k + Ad_Fᵀ g_R with
//! Ad_F − I = ad_{ξᵈ} dexp_{ξᵈ} (both power series in ad), so neither cancels for small steps.
//! The step is solved by the simplified Newton method (parent module, "Solving a step"): a
//! residual evaluates only the gradient of ℓ ([`super::group_equations`]), the Jacobian's
//! Hessian blocks only when the kept factors are refreshed.
//! The discrete Noether theorem holds as on SO(3): for a left-invariant L the spatial momentum
//! Ad_{g⁻¹}ᵀμ is conserved, since Ad_{g_{k+1}⁻¹}ᵀ Ad_Fᵀ = Ad_{g_k⁻¹}ᵀ.

use super::group_equations::{
    GroupDerivatives, GroupScratch, assemble_group, configuration_sum_at,
};
use super::tables::StepTables;
use super::{Form, LieSvi, ORTHOGONALITY_TOLERANCE, at_time, check_invariance};
use crate::error::{Error, StepFailure, require_finite_entries, require_positive};
use crate::method::group_space::{GroupInitial, GroupPoint, GroupSpace, GroupState};
use crate::method::space::Space;
use crate::method::step::Step;
use crate::method::{MethodInfo, StepReport};
use crate::model::group::{GroupLagrangian, GroupLagrangianExt, LieGroup};
use crate::nonlinear::{Jacobian, Newton};
use nalgebra::{DMatrix, DVector, SMatrix, SVector};

/// The largest group dimension N the dense derivatives support: each Gauss point differentiates
/// L in hyper-dual numbers with N + N directions (N² + 2N + 1 numbers each, on the stack), so
/// beyond this a model must supply structured derivatives ([`GroupLagrangian::STRUCTURED`],
/// such as the terms on pairs of links of a chain, [`crate::model::group::pair_terms`]).
pub const MAX_GROUP_DIMENSION: usize = 12;

/// The largest group dimension N with structured derivatives: chains of 32 links of SO(3)
/// (a step still forms a few N × N matrices on the stack, and its Newton matrix is dense).
pub const MAX_STRUCTURED_GROUP_DIMENSION: usize = 96;

/// [`MAX_GROUP_DIMENSION`] and [`MAX_STRUCTURED_GROUP_DIMENSION`] as typed errors (a forced
/// model's force is differentiated densely: at most [`MAX_GROUP_DIMENSION`]).
fn check_dimension<L: GroupLagrangian<N, E>, const N: usize, const E: usize>() -> Result<(), Error>
{
    let limit = if L::STRUCTURED {
        MAX_STRUCTURED_GROUP_DIMENSION
    } else {
        MAX_GROUP_DIMENSION
    };
    if N > limit {
        let reason = if L::STRUCTURED {
            format!("{N} exceeds {limit}, the largest group lie-svi runs")
        } else {
            format!(
                "{N} exceeds {limit}, the largest group lie-svi differentiates densely; a \
                 larger group (up to {MAX_STRUCTURED_GROUP_DIMENSION}) needs a model with \
                 structured derivatives (GroupLagrangian::STRUCTURED, as the chains of links \
                 written with model::group::pair_terms)"
            )
        };
        return Err(Error::invalid("group dimension", reason));
    }
    if L::FORCED && N > MAX_GROUP_DIMENSION {
        return Err(Error::invalid(
            "group dimension",
            format!(
                "{N}: a force (FORCED = true) is differentiated densely, on groups up to \
                 {MAX_GROUP_DIMENSION} only"
            ),
        ));
    }
    Ok(())
}

/// Tables, buffers and warm-start data of a [`LieSvi`] run on a group of dimension `N`.
#[derive(Debug, Clone)]
pub struct GroupWorkspace<const N: usize> {
    pub(super) tables: StepTables,
    pub(super) reduced: bool,
    /// ξ¹…ξᵈ, stacked.
    pub(super) unknowns: DVector<f64>,
    /// The previous step's ξ¹…ξᵈ.
    pub(super) previous: DVector<f64>,
    pub(super) has_previous: bool,
    points: Vec<GroupDerivatives<N>>,
    /// ∂g_R/∂ξʲ, j = 1..d.
    rates: Vec<SMatrix<f64, N, N>>,
    scratch: GroupScratch<N>,
    newton: Newton,
    /// Last body velocity from the inverse Legendre map (its Newton start).
    velocity_guess: SVector<f64, N>,
}

impl<const N: usize> GroupWorkspace<N> {
    /// Starting values: the previous step's curve extrapolated to the new nodes and moved to
    /// the chart at g_k (ξᵛ = log(exp(ξᵈ_prev)⁻¹ exp(ζ_ν))), or at the first step the
    /// uniform motion ξ(τ) = (τ + 1)(h/2) ξ₀.
    fn start<L: GroupLagrangian<N, E>, const E: usize>(
        &mut self,
        model: &L,
        h: f64,
        state: &GroupState<N, E>,
    ) {
        let d = self.tables.degree;
        if self.has_previous {
            let end = self.previous.fixed_rows::<N>(N * (d - 1)).into_owned();
            let back = L::Group::exp(&(-end));
            for nu in 1..=d {
                let zeta = self.tables.extrapolated::<N>(nu, &self.previous);
                let guess = L::Group::log(&L::Group::compose(&back, &L::Group::exp(&zeta)));
                self.unknowns
                    .fixed_rows_mut::<N>(N * (nu - 1))
                    .copy_from(&guess);
            }
        } else {
            let xi = model
                .velocity(&state.g, &state.momentum, &self.velocity_guess)
                .unwrap_or_else(|_| SVector::zeros());
            self.velocity_guess = xi;
            for nu in 1..=d {
                let guess = xi * (0.5 * h * (self.tables.nodes[nu] + 1.0));
                self.unknowns
                    .fixed_rows_mut::<N>(N * (nu - 1))
                    .copy_from(&guess);
            }
        }
    }
}

/// The space of a model on a group.
type S<L, const N: usize, const E: usize> = GroupSpace<<L as GroupLagrangian<N, E>>::Group, N, E>;

impl<L, const N: usize, const E: usize> Step<L, S<L, N, E>> for LieSvi
where
    L: GroupLagrangian<N, E>,
{
    type Workspace = GroupWorkspace<N>;

    fn info(&self) -> MethodInfo {
        LieSvi::info(self)
    }

    /// Validate the options (and the group's dimension, [`check_dimension`], and the model's
    /// structure, [`GroupLagrangian::check_structure`]) and
    /// build every table and buffer for steps of size `h`.
    fn workspace(&self, model: &L, h: f64) -> Result<GroupWorkspace<N>, Error> {
        check_dimension::<L, N, E>()?;
        model.check_structure()?;
        self.validate(L::G_INVARIANT)?;
        if self.form == Form::Reduced && L::FORCED {
            return Err(Error::invalid(
                "form",
                "the reduced Euler–Poincaré form needs an unforced model (FORCED = false)",
            ));
        }
        require_positive("h", h)?;
        let tables = StepTables::new(self.points, self.quadrature_points(), h)?;
        let degree = tables.degree;
        let m = tables.len();
        Ok(GroupWorkspace {
            tables,
            reduced: self.form == Form::Reduced,
            unknowns: DVector::zeros(N * degree),
            previous: DVector::zeros(N * degree),
            has_previous: false,
            points: vec![GroupDerivatives::zeros(); m],
            rates: vec![SMatrix::zeros(); degree],
            scratch: GroupScratch::new(),
            newton: Newton::new(N * degree, self.max_iterations).until_noise(),
            velocity_guess: SVector::zeros(),
        })
    }

    /// Advance (g_k, μ_k) by one step, writing (g_{k+1} − g_k, μ_{k+1} − μ_k) into
    /// `increment`. A step whose ξᵈ leaves the natural chart is
    /// [`StepFailure::OutsideChart`]. Allocates nothing.
    fn step(
        &self,
        model: &L,
        workspace: &mut GroupWorkspace<N>,
        t: f64,
        h: f64,
        state: &GroupState<N, E>,
        increment: &mut GroupState<N, E>,
    ) -> Result<StepReport, StepFailure> {
        if workspace.tables.h != h {
            workspace.tables.rescale(h);
            workspace.has_previous = false;
            workspace.newton.invalidate();
        }
        workspace.start(model, h, state);
        let GroupWorkspace {
            tables,
            reduced,
            unknowns,
            points,
            rates,
            scratch,
            newton,
            ..
        } = workspace;
        let last = N * (tables.degree - 1);
        // A start (ξᵈ ≈ h ξ) or an end outside the chart: the step is too large for it, and
        // that, not the Newton iteration, is what to report.
        let outside = |z: &DVector<f64>| {
            let reach = L::Group::chart_reach(&z.fixed_rows::<N>(last).into_owned());
            (reach >= 1.0).then_some(StepFailure::OutsideChart { reach })
        };
        if let Some(failure) = outside(unknowns) {
            return Err(failure);
        }
        // ξ moves g by g(exp ξ − e): it needs the accuracy of g's entries (rotations' are of
        // size 1), not of its own (small) size.
        newton.set_scale_floor(state.g.amax().min(1.0));
        let solved = newton
            .iterate(unknowns, Jacobian::Kept, |z, jacobian, residual| {
                assemble_group(
                    model, tables, *reduced, points, rates, scratch, t, state, z, jacobian,
                    residual,
                )
            })
            .map_err(|failure| outside(unknowns).unwrap_or(failure))?;
        if let Some(failure) = outside(unknowns) {
            return Err(failure);
        }
        let end = unknowns.fixed_rows::<N>(last).into_owned();
        // g_R at the converged nodes (the assembly's is one Newton iterate behind).
        let torque = configuration_sum_at(
            model,
            (tables, *reduced),
            (t, &state.g),
            unknowns,
            &mut scratch.maps,
        );
        let adjoint_minus_identity = L::Group::ad(&end) * L::Group::dexp(&end);
        increment.g = L::Group::translate_difference(&state.g, &L::Group::exp_minus_identity(&end));
        increment.momentum = adjoint_minus_identity.transpose() * state.momentum
            + (adjoint_minus_identity.transpose() * torque + torque);
        if !increment
            .g
            .iter()
            .chain(increment.momentum.iter())
            .all(|x| x.is_finite())
        {
            return Err(StepFailure::NonFinite);
        }
        workspace.previous.copy_from(&workspace.unknowns);
        workspace.has_previous = true;
        let m = workspace.tables.len();
        Ok(StepReport {
            iterations: solved.iterations,
            evaluations: m * (solved.iterations + 1),
            factorizations: solved.factorizations,
            analyses: 0,
        })
    }

    fn restart(&self, workspace: &mut GroupWorkspace<N>) {
        workspace.has_previous = false;
        workspace.newton.invalidate();
    }

    /// Not yet built on general groups: an [`StepFailure::Unsupported`] error (the exact
    /// tangent map exists on SO(3), [`crate::method::space::SO3`]).
    fn tangent_map(
        &self,
        _model: &L,
        _workspace: &mut GroupWorkspace<N>,
        _t: f64,
        _h: f64,
        _state: &GroupState<N, E>,
    ) -> Result<(GroupState<N, E>, DMatrix<f64>, StepReport), StepFailure> {
        Err(StepFailure::Unsupported {
            option: "tangent map",
            reason: "the exact tangent map of lie-svi is built on SO(3) only",
        })
    }

    /// Checks the group's dimension ([`check_dimension`]) and the initial
    /// condition: finite values, a configuration in the group ([`LieGroup::defect`] at most
    /// [`ORTHOGONALITY_TOLERANCE`]) and an invertible Legendre map.
    fn initial_state(
        &self,
        model: &L,
        t0: f64,
        initial: &GroupInitial<N, E>,
    ) -> Result<GroupState<N, E>, Error> {
        check_dimension::<L, N, E>()?;
        let (g, second, name) = match initial {
            GroupInitial::Velocity { g, xi } => (g, xi, "initial body velocity"),
            GroupInitial::Momentum { g, momentum } => (g, momentum, "initial body momentum"),
        };
        require_finite_entries("initial configuration", g)?;
        require_finite_entries(name, second)?;
        let defect = L::Group::defect(g);
        if defect > ORTHOGONALITY_TOLERANCE {
            return Err(Error::invalid(
                "initial configuration",
                format!(
                    "not in {}: its distance from the group (‖RᵀR − I‖ of a rotation, or a \
                     reflection) is {defect:e}",
                    L::Group::NAME
                ),
            ));
        }
        let momentum = match initial {
            GroupInitial::Momentum { momentum, .. } => *momentum,
            GroupInitial::Velocity { g, xi } => model.momentum(g, xi),
        };
        let state = GroupState { g: *g, momentum };
        if !state.momentum.iter().all(|x| x.is_finite()) {
            return Err(Error::NonFinite {
                what: "initial state".into(),
                step: 0,
                t: t0,
            });
        }
        // The Legendre map must be invertible at the start (a singular inertia is not).
        self.complete(
            model,
            None,
            t0,
            &state,
            &S::<L, N, E>::initial_guess(initial),
        )?;
        Ok(state)
    }

    /// A G-invariance declaration: L(g, ξ) = L(e, ξ) and a zero configuration gradient at
    /// the initial state.
    fn check_model(&self, model: &L, t0: f64, state: &GroupState<N, E>) -> Result<(), Error> {
        if !L::G_INVARIANT {
            return Ok(());
        }
        let xi = self.complete(model, None, t0, state, &SVector::zeros())?.xi;
        let here = model.value(&state.g, &xi);
        let identity = model.value(&L::Group::identity(), &xi);
        let gradient = model.configuration_gradient(&state.g, &xi).amax();
        let scale = 1.0 + here.abs() + state.momentum.amax() * (1.0 + xi.amax());
        check_invariance("L(g, ξ) = L(e, ξ)", here - identity, gradient, scale)
    }

    /// ξ from μ by the inverse Legendre map started at `guess`.
    fn complete(
        &self,
        model: &L,
        _workspace: Option<&GroupWorkspace<N>>,
        t: f64,
        state: &GroupState<N, E>,
        guess: &SVector<f64, N>,
    ) -> Result<GroupPoint<N, E>, Error> {
        let xi = model
            .velocity(&state.g, &state.momentum, guess)
            .map_err(at_time(t))?;
        Ok(GroupPoint {
            t,
            g: state.g,
            xi,
            momentum: state.momentum,
        })
    }

    fn incomplete(
        &self,
        t: f64,
        state: &GroupState<N, E>,
        guess: &SVector<f64, N>,
    ) -> GroupPoint<N, E> {
        GroupPoint {
            t,
            g: state.g,
            xi: *guess,
            momentum: state.momentum,
        }
    }

    fn point_is_finite(&self, point: &GroupPoint<N, E>) -> bool {
        point
            .xi
            .iter()
            .chain(point.momentum.iter())
            .all(|x| x.is_finite())
    }

    /// The step curve g_k exp(ξ(τ)) at τ = 2(time − t)/h − 1, with the body velocity
    /// dexp_{−ξ} ξ̇ and μ = ∂L/∂ξ there.
    fn dense_point(
        &self,
        model: &L,
        workspace: &GroupWorkspace<N>,
        t: f64,
        h: f64,
        start: &GroupState<N, E>,
        time: f64,
    ) -> Option<GroupPoint<N, E>> {
        if !workspace.has_previous {
            return None;
        }
        let tau = 2.0 * ((time - t) / h).clamp(0.0, 1.0) - 1.0;
        let (xi, rate) = workspace.tables.curve::<N>(tau, h, &workspace.previous);
        let g = L::Group::compose(&start.g, &L::Group::exp(&xi));
        let velocity = L::Group::body_velocity(&xi, &rate);
        Some(GroupPoint {
            t: time,
            g,
            xi: velocity,
            momentum: model.momentum(&g, &velocity),
        })
    }

    fn points(&self) -> Option<usize> {
        Some(self.points)
    }

    fn with_points(&self, points: usize) -> Option<Self> {
        Some(self.with_point_count(points))
    }

    /// ξ¹, …, ξᵈ of the last step (ξ⁰ = 0).
    fn node_offsets<'a>(&self, workspace: &'a mut GroupWorkspace<N>) -> Option<&'a [f64]> {
        workspace
            .has_previous
            .then_some(workspace.previous.as_slice())
    }
}
