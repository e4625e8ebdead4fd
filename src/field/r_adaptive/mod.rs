//! r-adaptive (moving-mesh) multisymplectic variational integrators of a 1 + 1 field (Leok,
//! *Generalized Variational Integrators*, §5.6, on the multisymplectic VI of §5.1.3): the
//! nodes x_i(t) of the spatial mesh are unknowns beside the field values, and move so that
//! they cluster where the field is steep.
//!
//! # The action in computational variables (§5.6)
//! A regular computational mesh R = {(ξ, τ)} (cells of unit width in ξ, levels t_j = t₀ + jΔt)
//! is mapped to the physical space-time X by φ(ξ, τ) = (x(ξ, τ), t₀ + τΔt). A field u on X
//! is represented by its pull-back ũ = u ∘ φ on R, and the action becomes
//!
//! S\[u\] = ∫_X ℒ(j¹u) dx dt = ∫_R ℒ(x, t, ũ, u_t, u_x) |Dφ| dξ dτ,
//! u_x = ũ_ξ / x_ξ,  u_t = (ũ_τ − u_x x_τ)/Δt,  |Dφ| = x_ξ Δt.
//!
//! Both ũ and x are bilinear on each computational cell, with nodal values u_{i,j}, x_{i,j};
//! a cell's discrete Lagrangian is the [`CellQuadrature`] of the pulled-back integrand,
//!
//! L_d(q₀, q₁, q₂, q₃) = Δt Σ_q w_q x_ξ ℒ(x, t, ũ, u_t, u_x)(ξ_q, τ_q),  q_k = (u_k, x_k),
//!
//! (corners 0 = (i, j), 1 = (i + 1, j), 2 = (i, j + 1), 3 = (i + 1, j + 1)): the
//! multisymplectic discrete Lagrangian of §5.1.3 for the enlarged configuration q = (u, x) ∈
//! ℝᶜ⁺¹ on the *regular* mesh R. With x_{i,j} = a + iΔx fixed it is exactly the uniform
//! integrator's ([`crate::field::multisymplectic`]).
//!
//! # Why constraints, and which
//! S is invariant under reparametrisations of R (ξ ↦ ψ(ξ, τ) leaves ∫_X unchanged), so its
//! Euler–Lagrange equation in x is a consequence of the one in u and says nothing about where
//! the nodes should go: the pulled-back Lagrangian is degenerate in x_τ (its kinetic part
//! ½x_ξ(ũ_τ − u_x x_τ)²/Δt² has rank C in (ũ_τ, x_τ)). The mesh is fixed instead by an
//! equidistribution principle imposed as holonomic constraints with Lagrange multipliers in
//! the discrete action (the constrained variational integrators of Marsden & West 2001, §3.5;
//! the "Lagrange multiplier approach" of Tyranowski & Desbrun, *r-adaptive multisymplectic
//! and variational integrators*, 2019):
//!
//! S_d = Σ_j [ Σ_cells L_d(slab j) + Σ_i λ_i^j g_i(q^j) ],
//!
//! g_i(q) = ω_i ñ_{i−1} − ω_{i−1} ñ_i  (interior nodes i = 1 … N − 1 of N cells),
//!
//! with the cell widths h_k = x_{k+1} − x_k, the mesh concentrations n_k = 1/h_k smoothed as
//! in Dorfi & Drury (1987), ñ_k = n_k − κ(κ + 1)(n_{k+1} − 2n_k + n_{k−1}) (n_{−1} = n_0,
//! n_N = n_{N−1}), and a cell monitor ω_k ([`Monitor`]). For κ = 0 the constraints say
//! ω_k h_k = const: every cell carries the same share of ∫ω dx (the arc length, for
//! ω = √(1 + α|u_x|²)); κ > 0 keeps neighbouring cells within the ratio (κ + 1)/κ of each
//! other, which keeps the map φ smooth.
//!
//! # Discrete equations
//! Varying q^j and λ^j gives, at every interior node i and level j,
//!
//! p^j_i + Σ_{cells of slab j at i} D_{0|1} L_d(q^j, q^{j+1}) + Σ_m λ_m^j ∇_{q_i} g_m(q^j) = 0,
//! g(q^{j+1}) = 0,
//! p^{j+1}_i = Σ_{cells of slab j at i} D_{2|3} L_d(q^j, q^{j+1}),
//!
//! the four-term DEL of §5.1.3 in q = (u, x) with the two cells below folded into the
//! discrete momentum p^j (C + 1 components per node), plus the constraint forces. Each level
//! solves (C + 2)(N − 1) equations for u^{j+1}, x^{j+1} and λ^j by Newton's method (the
//! Jacobian is banded, 5 nodes wide, and factored by faer's sparse LU). The cell derivatives
//! D_k L_d and D_k D_l L_d and the constraint gradients come by automatic differentiation
//! (num-dual) of the discrete Lagrangian and of g, never by hand. The initial momenta are the
//! Legendre transform of the given velocity: p_{u,i} = π_i w_i, p_{x,i} = −π_i·u_x w_i with
//! π = ∂ℒ/∂u_t and w_i = (x_{i+1} − x_{i−1})/2 (the mesh velocity does not enter; any part of
//! p normal to the constraints is absorbed by λ⁰). The initial mesh equidistributes the
//! initial field (de Boor's fixed point, each iterate solved by Newton).
//!
//! # Which structure is kept
//! - **Symplecticity on the constraint manifold.** The level map (q^j, p^j) ↦ (q^{j+1},
//!   p^{j+1}) is the discrete flow of the constrained discrete Lagrangian
//!   Σ_cells L_d(q^j, q^{j+1}) restricted to {g = 0}, hence symplectic there (Marsden & West
//!   §3.5). Equivalently, the scheme is multisymplectic *in the computational variables*
//!   (u, x) on R for the augmented local action Σ L_d + Σ λ g, since both terms are local:
//!   the discrete multisymplectic form formula of §5.1.3 holds with the constraint terms as
//!   extra local contributions. It is not multisymplectic on the physical mesh.
//! - **Energy.** Not conserved exactly; the discrete energy of slab j,
//!   E^{j+½} = Σ_cells Σ_q w_q x_ξ (π·u_t − ℒ)(q), stays bounded with no drift for
//!   autonomous densities (a consequence of symplecticity, checked over 10⁴ levels in the
//!   tests).
//! - **Momentum.** The equidistribution constraints with the ends held fixed are not
//!   invariant under translations of x, so the physical momentum −∫π·u_x dx is not a discrete
//!   Noether quantity; it is reported, not conserved. (The "horizontal" momentum that the
//!   constraint-free scheme would conserve, §5.5 and the chapter's closing remarks, is traded
//!   for the equidistribution.)
//! - **The uniform VI as a special case.** With [`Monitor::Uniform`] the constraints hold the
//!   nodes at x_i = a + iΔx, the x-equations only determine λ, and the field equations are
//!   exactly those of [`crate::field::multisymplectic::Multisymplectic`] (tested).
//!
//! # Limits
//! **Fast collisions.** The kink–antikink pair (arc length, α = 1) runs through its collision
//! at v ≤ 0.4, but at v = 0.5 or 0.9 (or at v = 0.3 with α = 4) the level's Newton iteration
//! stops converging shortly before the collision, with a typed [`Error::NonConvergence`]:
//! at v = 0.9 at t ≈ −0.8 on 101, 201 or 401 nodes and for Δt = 0.05 or 0.0125 alike, so it
//! is a singularity of the constrained mesh dynamics, not of the resolution. Measured on
//! the way there (201 nodes): the multipliers grow, doubling every 0.25 time units, in a mode
//! nearly constant over each flat outer region. There ω ≈ 1, the constraints
//! g_i ≈ ñ_{i−1} − ñ_i telescope, and Σλ_i ∇g_i of a constant λ vanishes but at the ends of the
//! region: that mode is the level Jacobian's smallest singular value (6·10⁻⁴ against
//! 2·10⁴ at the failing level's start), and the Jacobian turns singular along the iteration.
//! It is the degenerate Legendre transform of the pulled-back Lagrangian (singular wherever
//! three nodes line up, Tyranowski's thesis §4.2) that only the constraints regularise, and
//! they do so weakly where the field is flat. A mesh kinetic energy ½ε x_t² per unit length
//! (the regularisation that thesis suggests) was tried and made it worse: the failure came at
//! t = −0.75 for ε = 0.01 and at t = −1.5 for ε = 0.1.
//!
//! Dirichlet boundaries only (the end nodes are held at the domain's ends); densities that do
//! not depend on x explicitly (the [`LagrangianDensity`] trait passes x as `f64`, so ∂ℒ/∂x,
//! which the x-equations need, is not available; such densities are rejected). A mesh that
//! folds (a cell of width ≤ 0 after a level) is an [`Error::MeshFold`] with the step and time.
//! Order 2 in (Δξ, Δt) for a smooth map φ.
//!
//! # Measured (2026-12-06, release build, one job, 2-core machine)
//! Sine-Gordon kink at v = 0.99 (γ = 7.09) from x₀ = −10 on [−20, 20] to T = 20, largest
//! nodal error against the exact kink over all levels: the r-adaptive VI (midpoint, arc
//! length α = 4, κ = 2, Δt = 0.05) 7.7·10⁻² on 101 nodes in 0.41 s; the uniform VI
//! (trapezoid, Δt = Δx/2) 8.6·10⁻² on 3201 nodes in 1.9 s, 0.16 on 2401 nodes. The
//! breather's discrete energy over 10⁴ levels varies by 2.9·10⁻² (0.2 % of E = 13.95) with
//! no drift. The kink–antikink pair at v = 0.4 runs through its collision on 201 nodes within
//! 5.8·10⁻² of the exact pair; faster pairs do not (see *Limits*).
//!
//! # Which quadrature
//! [`CellQuadrature::Midpoint`] (the default here) is the box scheme in computational
//! variables, stable for every Δt on the wave equation: the mesh follows a fast kink, so
//! the solution varies slowly along the moving nodes and Δt may be much larger than the
//! smallest cell. [`CellQuadrature::Trapezoid`] is the leapfrog scheme in computational
//! variables: implicit here (the x-equations are nonlinear), and limited by the smallest
//! cell's CFL condition measured relative to the moving mesh.

mod cell;
mod equidistribution;
mod level;
#[cfg(test)]
mod tests;

use crate::error::{Error, require_finite};
use crate::field::mesh::MAX_POINTS;
pub use crate::field::multisymplectic::CellQuadrature;
use crate::field::multisymplectic::check_newton;
use crate::model::density::{Boundary, Domain, Jet, LagrangianDensity, LagrangianDensityExt};
use cell::QuadraturePoint;
use nalgebra::SVector;

/// The smallest number of nodes of a moving mesh (three cells: the smoothed equidistribution
/// needs two neighbours of each interior cell).
pub const MIN_NODES: usize = 4;

/// The monitor function ω of the equidistribution (ω_k h_k equal in every cell when the
/// smoothing is 0). Cell values use the cell slope s_k = (u_{k+1} − u_k)/h_k and, for the
/// curvature, c_k = (s_{k+1} − s_{k−1})/(m_{k+1} − m_{k−1}) with cell centres m_k (one-sided
/// at the ends).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Monitor {
    /// ω = 1: a uniform mesh (the r-adaptive integrator then reduces to the uniform one).
    Uniform,
    /// The arc-length monitor ω = √(1 + α|u_x|²); α scales the field against x (α = 1: the
    /// arc length of the graph).
    ArcLength {
        /// α ≥ 0.
        scale: f64,
    },
    /// The curvature-weighted monitor ω = √(1 + α|u_x|² + β|u_xx|²): adds nodes where the
    /// slope changes (the shoulders of a kink) as well as where it is steep.
    Curvature {
        /// α ≥ 0, the weight of the slope.
        scale: f64,
        /// β ≥ 0, the weight of the curvature.
        curvature: f64,
    },
}

impl Default for Monitor {
    fn default() -> Self {
        Monitor::ArcLength { scale: 1.0 }
    }
}

/// Options of [`RAdaptive`].
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct RAdaptiveOptions {
    /// The number of nodes N + 1 in space (N cells), at least [`MIN_NODES`].
    pub nodes: usize,
    /// The time step Δt.
    pub dt: f64,
    /// The monitor of the equidistribution.
    pub monitor: Monitor,
    /// The smoothing parameter κ ≥ 0 of the mesh concentration (Dorfi & Drury): neighbouring
    /// cells stay within the width ratio (κ + 1)/κ; 0 is plain equidistribution.
    pub smoothing: f64,
    /// The cell quadrature (see the module docs; [`CellQuadrature::Midpoint`] by default).
    pub quadrature: CellQuadrature,
    /// Iteration cap of Newton's method per level (and of the initial equidistribution).
    pub max_iterations: usize,
    /// Newton stops when ‖Δz‖∞ ≤ tolerance · (1 + ‖z‖∞) (z: field values, node positions and
    /// multipliers of the level).
    pub tolerance: f64,
    /// The starting mesh of the initial equidistribution (N + 1 strictly increasing positions
    /// from the left end of the domain to its right end); `None`: the uniform mesh.
    pub initial_mesh: Option<Vec<f64>>,
    /// Keep every k-th level in [`AdaptiveRun`] (the first and the last are always kept);
    /// at least 1.
    pub record_every: usize,
}

impl Default for RAdaptiveOptions {
    fn default() -> Self {
        RAdaptiveOptions {
            nodes: 101,
            dt: 0.05,
            monitor: Monitor::default(),
            smoothing: 2.0,
            quadrature: CellQuadrature::Midpoint,
            max_iterations: 50,
            tolerance: 1e-12,
            initial_mesh: None,
            record_every: 1,
        }
    }
}

/// What [`RAdaptive::run`] returns: the kept levels (times, node positions, field values),
/// and per slab the energy and momentum.
#[derive(Debug, Clone, PartialEq)]
pub struct AdaptiveRun<const C: usize> {
    /// The level index j of each kept level.
    pub levels: Vec<usize>,
    /// t_j of each kept level.
    pub times: Vec<f64>,
    /// The node positions x_0 … x_N of each kept level.
    pub positions: Vec<Vec<f64>>,
    /// The field values u_0 … u_N of each kept level.
    pub fields: Vec<Vec<SVector<f64, C>>>,
    /// The discrete energy E^{j+½} = Σ_cells Σ_q w_q x_ξ (π·u_t − ℒ)(q) of each slab
    /// [t_j, t_{j+1}], j = 0, 1, … (ℒ and π at the physical jet of the interpolant).
    pub energy: Vec<f64>,
    /// The discrete momentum P^{j+½} = −Σ_cells Σ_q w_q x_ξ (π·u_x)(q) of each slab.
    pub momentum: Vec<f64>,
    /// The smallest cell width over the run.
    pub smallest_width: f64,
    /// Newton iterations over the run.
    pub newton_iterations: usize,
    /// Factorisations of the level Jacobian over the run.
    pub factorizations: usize,
}

/// The r-adaptive multisymplectic variational integrator of a [`LagrangianDensity`] with
/// Dirichlet ends (see the [module docs](self)).
#[derive(Debug, Clone)]
pub struct RAdaptive<F, const C: usize> {
    density: F,
    domain: Domain,
    left: SVector<f64, C>,
    right: SVector<f64, C>,
    options: RAdaptiveOptions,
    points: Vec<QuadraturePoint>,
}

impl<F: LagrangianDensity<C>, const C: usize> RAdaptive<F, C> {
    /// The integrator of `density` on `domain` with `boundary` (which must be
    /// [`Boundary::Dirichlet`]).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] named `nodes` (fewer than [`MIN_NODES`] or more than
    /// [`MAX_POINTS`]), `dt` (not finite and positive), `monitor.scale` or
    /// `monitor.curvature` (not finite and ≥ 0), `smoothing` (not finite and ≥ 0),
    /// `max_iterations` (zero), `tolerance` (not finite and positive), `record_every` (zero),
    /// `initial_mesh` (wrong length, non-finite, ends off the domain's ends, or not strictly
    /// increasing) or `boundary` (periodic, or a non-finite Dirichlet value).
    pub fn new(
        density: F,
        domain: Domain,
        boundary: Boundary<C>,
        options: RAdaptiveOptions,
    ) -> Result<Self, Error> {
        let nodes = options.nodes;
        if !(MIN_NODES..=MAX_POINTS).contains(&nodes) {
            return Err(Error::invalid(
                "nodes",
                format!(
                    "{nodes} nodes in space: a moving mesh needs from {MIN_NODES} to {MAX_POINTS} nodes"
                ),
            ));
        }
        crate::error::require_positive("dt", options.dt)?;
        let non_negative = |name: &str, value: f64| {
            if value.is_finite() && value >= 0.0 {
                Ok(())
            } else {
                Err(Error::invalid(
                    name,
                    format!("{value:?} must be finite and non-negative"),
                ))
            }
        };
        match options.monitor {
            Monitor::Uniform => {}
            Monitor::ArcLength { scale } => non_negative("monitor.scale", scale)?,
            Monitor::Curvature { scale, curvature } => {
                non_negative("monitor.scale", scale)?;
                non_negative("monitor.curvature", curvature)?;
            }
        }
        non_negative("smoothing", options.smoothing)?;
        check_newton(options.max_iterations, options.tolerance)?;
        if options.record_every == 0 {
            return Err(Error::invalid("record_every", "must be at least 1"));
        }
        let Boundary::Dirichlet { left, right } = boundary else {
            return Err(Error::invalid(
                "boundary",
                "the r-adaptive integrator holds the end nodes at the domain's ends and needs Dirichlet values there (a periodic mesh is not supported)",
            ));
        };
        if !left.iter().chain(right.iter()).all(|v| v.is_finite()) {
            return Err(Error::invalid(
                "boundary",
                "a Dirichlet value is not finite",
            ));
        }
        if let Some(mesh) = &options.initial_mesh {
            check_initial_mesh(mesh, nodes, domain)?;
        }
        let points = cell::quadrature_points(options.quadrature);
        Ok(RAdaptive {
            density,
            domain,
            left,
            right,
            options,
            points,
        })
    }

    /// The options.
    pub fn options(&self) -> &RAdaptiveOptions {
        &self.options
    }

    /// Run `levels` time levels from t0, starting from the field (u, u_t) = `initial(x)` on
    /// the mesh that equidistributes it. `observe(j, t_j, x^j, u^j)` sees every level, the
    /// initial one (j = 0) included; the result keeps every
    /// [`RAdaptiveOptions::record_every`]-th level.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for a non-finite t0 or initial field (`initial`), an
    /// initial field that disagrees with the Dirichlet values (`boundary`) or a density that
    /// depends on x explicitly (`density`). [`Error::NonConvergence`] of the initial
    /// equidistribution (step 0). During the run: [`Error::MeshFold`],
    /// [`Error::NonConvergence`], [`Error::SingularMatrix`] or [`Error::NonFinite`] with the
    /// level index and its time.
    pub fn run(
        &self,
        t0: f64,
        initial: impl Fn(f64) -> (SVector<f64, C>, SVector<f64, C>),
        levels: usize,
        mut observe: impl FnMut(usize, f64, &[f64], &[SVector<f64, C>]),
    ) -> Result<AdaptiveRun<C>, Error> {
        require_finite("t0", t0)?;
        let dt = self.options.dt;
        let sample = |x: f64| -> Result<(SVector<f64, C>, SVector<f64, C>), Error> {
            let (u, v) = initial(x);
            if u.iter().chain(v.iter()).all(|x| x.is_finite()) {
                Ok((u, v))
            } else {
                Err(Error::invalid(
                    "initial",
                    format!("the initial field is not finite at x = {x:?}"),
                ))
            }
        };
        for (x, value, end) in [
            (self.domain.left(), self.left, "left"),
            (self.domain.right(), self.right, "right"),
        ] {
            let u = sample(x)?.0;
            let gap = (u - value).amax();
            if gap > 1e-6 * (1.0 + value.amax()) {
                return Err(Error::invalid(
                    "boundary",
                    format!(
                        "the initial field at the {end} end, {:?}, differs from the Dirichlet value {:?} by {gap:e}",
                        u.as_slice(),
                        value.as_slice()
                    ),
                ));
            }
        }
        let x = self.initial_mesh(t0, &|x| sample(x).map(|(u, _)| u))?;
        let last = x.len() - 1;
        let mut u = Vec::with_capacity(x.len());
        let mut velocity = Vec::with_capacity(x.len());
        for &position in &x {
            let (value, rate) = sample(position)?;
            u.push(value);
            velocity.push(rate);
        }
        u[0] = self.left;
        u[last] = self.right;
        let (momentum_u, momentum_x) = self.initial_momentum(t0, &x, &u, &velocity)?;
        let mut state = level::State {
            x,
            u,
            multipliers: vec![0.0; last + 1],
            momentum_u,
            momentum_x,
        };
        // A virtual level at t0 − Δt, the mesh that equidistributes u⁰ − Δt u_t⁰ and that
        // field on it, starts the first Newton iteration (extrapolated through level 0).
        // (Taking p⁰ = Σ D_{2|3} L_d of the slab below level 0 instead of the Legendre
        // transform made the kink at v = 0.99 less accurate: 0.35 against 0.20 on 101 nodes.)
        let behind_x = self.initial_mesh(t0, &|x| sample(x).map(|(u, v)| u - v * dt))?;
        let mut behind_u = Vec::with_capacity(last + 1);
        for &position in &behind_x {
            let (value, rate) = sample(position)?;
            behind_u.push(value - rate * dt);
        }
        behind_u[0] = self.left;
        behind_u[last] = self.right;
        let mut previous = Some((behind_x, behind_u));
        let mut run = AdaptiveRun {
            levels: Vec::new(),
            times: Vec::new(),
            positions: Vec::new(),
            fields: Vec::new(),
            energy: Vec::with_capacity(levels),
            momentum: Vec::with_capacity(levels),
            smallest_width: smallest_width(&state.x).1,
            newton_iterations: 0,
            factorizations: 0,
        };
        let record = |run: &mut AdaptiveRun<C>, j: usize, t: f64, state: &level::State<C>| {
            run.levels.push(j);
            run.times.push(t);
            run.positions.push(state.x.clone());
            run.fields.push(state.u.clone());
        };
        observe(0, t0, &state.x, &state.u);
        record(&mut run, 0, t0, &state);
        let mut solver = level::LevelSolver::new(self, last + 1)?;
        for j in 0..levels {
            let t = t0 + j as f64 * dt;
            let (energy, momentum) = solver.step(self, j, t, &mut state, &mut previous)?;
            run.energy.push(energy);
            run.momentum.push(momentum);
            let width = check_fold(j, t, &state.x)?;
            run.smallest_width = run.smallest_width.min(width);
            let t_next = t0 + (j + 1) as f64 * dt;
            observe(j + 1, t_next, &state.x, &state.u);
            if (j + 1) % self.options.record_every == 0 || j + 1 == levels {
                record(&mut run, j + 1, t_next, &state);
            }
        }
        run.newton_iterations = solver.iterations;
        run.factorizations = solver.factorizations;
        Ok(run)
    }

    /// The initial discrete momenta p_{u,i} = π_i w_i and p_{x,i} = −π_i·u_x w_i, with u_x by
    /// the second-order three-point difference on the non-uniform mesh and the dual cell
    /// width w_i = (x_{i+1} − x_{i−1})/2; checks on the way that ℒ does not depend on x.
    fn initial_momentum(
        &self,
        t0: f64,
        x: &[f64],
        u: &[SVector<f64, C>],
        velocity: &[SVector<f64, C>],
    ) -> Result<(Vec<SVector<f64, C>>, Vec<f64>), Error> {
        let last = x.len() - 1;
        let mut momentum_u = vec![SVector::zeros(); last + 1];
        let mut momentum_x = vec![0.0; last + 1];
        let length = self.domain.length();
        for i in 1..last {
            let (left, right) = (x[i] - x[i - 1], x[i + 1] - x[i]);
            let u_x = ((u[i + 1] - u[i]) * (left * left) + (u[i] - u[i - 1]) * (right * right))
                / (left * right * (left + right));
            let jet = Jet {
                u: u[i],
                u_t: velocity[i],
                u_x,
            };
            let g = self.density.gradient(x[i], t0, &jet);
            let shifted = self.density.gradient(x[i] + 0.37 * length, t0, &jet);
            if (shifted.value - g.value).abs() > 1e-12 * (1.0 + g.value.abs())
                || (shifted.u_t - g.u_t).amax() > 1e-12 * (1.0 + g.u_t.amax())
            {
                return Err(Error::invalid(
                    "density",
                    format!(
                        "ℒ depends on x explicitly (at x = {:?}); the r-adaptive integrator needs ∂ℒ/∂x, which the LagrangianDensity trait does not provide",
                        x[i]
                    ),
                ));
            }
            let width = 0.5 * (x[i + 1] - x[i - 1]);
            momentum_u[i] = g.u_t * width;
            momentum_x[i] = -g.u_t.dot(&u_x) * width;
        }
        Ok((momentum_u, momentum_x))
    }
}

/// The smallest cell width of mesh `x` after step `step` (from t), or [`Error::MeshFold`] when
/// a cell has width ≤ 0 (or NaN).
fn check_fold(step: usize, t: f64, x: &[f64]) -> Result<f64, Error> {
    let (cell, width) = smallest_width(x);
    if width.is_nan() || width <= 0.0 {
        return Err(Error::MeshFold {
            step,
            t,
            cell,
            width,
        });
    }
    Ok(width)
}

/// The first cell of smallest width and that width.
fn smallest_width(x: &[f64]) -> (usize, f64) {
    let mut best = (0, f64::INFINITY);
    for (k, pair) in x.windows(2).enumerate() {
        let width = pair[1] - pair[0];
        if width.is_nan() {
            return (k, width);
        }
        if width < best.1 {
            best = (k, width);
        }
    }
    best
}

/// Check a user's starting mesh: N + 1 finite, strictly increasing positions from the left
/// end of `domain` to its right end (within 10⁻⁹ of its length).
fn check_initial_mesh(mesh: &[f64], nodes: usize, domain: Domain) -> Result<(), Error> {
    if mesh.len() != nodes {
        return Err(Error::invalid(
            "initial_mesh",
            format!("{} positions for {nodes} nodes", mesh.len()),
        ));
    }
    if let Some((i, x)) = mesh.iter().enumerate().find(|(_, x)| !x.is_finite()) {
        return Err(Error::invalid(
            "initial_mesh",
            format!("x[{i}] = {x:?} is not finite"),
        ));
    }
    let slack = 1e-9 * domain.length();
    let (first, last) = (mesh[0], mesh[nodes - 1]);
    if (first - domain.left()).abs() > slack || (last - domain.right()).abs() > slack {
        return Err(Error::invalid(
            "initial_mesh",
            format!(
                "the mesh runs from {first:?} to {last:?}, not from the domain's ends {:?} to {:?}",
                domain.left(),
                domain.right()
            ),
        ));
    }
    if let Some(k) = mesh.windows(2).position(|pair| pair[1] <= pair[0]) {
        return Err(Error::invalid(
            "initial_mesh",
            format!(
                "not strictly increasing: x[{}] = {:?} ≥ x[{}] = {:?}",
                k,
                mesh[k],
                k + 1,
                mesh[k + 1]
            ),
        ));
    }
    Ok(())
}
