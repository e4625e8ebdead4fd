//! The stepping loop allocates nothing for fixed-size models: a run of 2000 steps performs
//! exactly as many heap allocations as a run of 20 (all of them in the set-up: workspace,
//! tables), for every method, both solver paths (fixed point and Newton) and the forced
//! paths, after a first run that fills the process-wide tables.

use crate::allocations;

use nalgebra::{Const, SVector};
use svi::method::any::AnyMethod;
use svi::method::hamiltonian::{
    HamiltonianCollocation, HamiltonianGalerkin, ImplicitMidpoint, Partitioned,
};
use svi::method::multiscale::Multiscale;
use svi::{
    AdjointSymplecticEuler, Canonical, Composition, Hamiltonian, HamiltonianStructure, Integrator,
    Lagrangian, Method, Midpoint, Scalar, Scheme, SpectralCollocation, StormerVerlet, Svi,
    SymplecticEuler, Trapezoid, VariationalIntegrator,
};
use svi_models::{DampedPendulum, DoublePendulum, Kepler, SpringPendulum};

/// Allocations of a run of `steps` steps of size 0.01.
fn allocations<L: Lagrangian<Const<N>> + Clone, M: Method<Const<N>> + Clone, const N: usize>(
    model: &L,
    method: &M,
    q: SVector<f64, N>,
    v: SVector<f64, N>,
    steps: usize,
) -> usize {
    let integrator = Integrator::new(model.clone(), method.clone());
    let before = allocations::count();
    integrator
        .run_from_velocity(0.0, q, v, 0.01, 0.01 * steps as f64, &mut ())
        .unwrap();
    allocations::count() - before
}

fn assert_loop_allocates_nothing<
    L: Lagrangian<Const<N>> + Clone,
    M: Method<Const<N>> + Clone,
    const N: usize,
>(
    model: L,
    method: M,
    q: SVector<f64, N>,
    v: SVector<f64, N>,
) {
    // One run first: what the process computes once (SC's order per number of points) is
    // not the loop's.
    allocations(&model, &method, q, v, 1);
    let short = allocations(&model, &method, q, v, 20);
    let long = allocations(&model, &method, q, v, 2000);
    assert_eq!(
        short,
        long,
        "{}: the step loop allocates",
        method.info().name
    );
}

#[test]
fn fixed_point_paths_do_not_allocate_per_step() {
    let (q, v) = (SVector::from([0.5, 0.0]), SVector::from([0.0, 3f64.sqrt()]));
    assert_loop_allocates_nothing(Kepler::default(), Svi::new(7).with_quadrature(6), q, v);
    assert_loop_allocates_nothing(Kepler::default(), Svi::new(6), q, v);
    assert_loop_allocates_nothing(Kepler::default(), SpectralCollocation::new(6), q, v);
}

#[test]
fn newton_paths_do_not_allocate_per_step() {
    let (q, v) = (SVector::from([1.0, 0.5]), SVector::from([0.0, 0.0]));
    assert_loop_allocates_nothing(DoublePendulum::default(), Svi::new(5), q, v);
    assert_loop_allocates_nothing(DoublePendulum::default(), SpectralCollocation::new(5), q, v);
}

#[test]
fn classic_methods_do_not_allocate_per_step() {
    let (q, v) = (SVector::from([0.5, 0.0]), SVector::from([0.0, 3f64.sqrt()]));
    let kepler = Kepler::default();
    assert_loop_allocates_nothing(kepler, VariationalIntegrator::new(SymplecticEuler), q, v);
    let adjoint = VariationalIntegrator::new(AdjointSymplecticEuler);
    assert_loop_allocates_nothing(kepler, adjoint, q, v);
    assert_loop_allocates_nothing(kepler, VariationalIntegrator::new(Midpoint), q, v);
    assert_loop_allocates_nothing(kepler, VariationalIntegrator::new(Trapezoid), q, v);
    assert_loop_allocates_nothing(kepler, StormerVerlet::default(), q, v);
    let (q, v) = (SVector::from([1.0, 0.5]), SVector::from([0.0, 0.0]));
    assert_loop_allocates_nothing(DoublePendulum::default(), StormerVerlet::default(), q, v);
}

#[test]
fn forced_paths_do_not_allocate_per_step() {
    let (q, v) = (SVector::from([1.0]), SVector::from([0.0]));
    let model = DampedPendulum::default();
    assert_loop_allocates_nothing(model, Svi::new(5), q, v);
    assert_loop_allocates_nothing(model, SpectralCollocation::new(5), q, v);
    assert_loop_allocates_nothing(model, VariationalIntegrator::new(Midpoint), q, v);
    assert_loop_allocates_nothing(model, StormerVerlet::default(), q, v);
    // The explicit kicks with a Newton solve on the velocity (a friction force).
    assert_loop_allocates_nothing(model, VariationalIntegrator::new(SymplecticEuler), q, v);
    let adjoint = VariationalIntegrator::new(AdjointSymplecticEuler);
    assert_loop_allocates_nothing(model, adjoint, q, v);
}

/// A relativistic oscillator written as H = √(1 + p²) + q²/2 (separable, explicit
/// Störmer–Verlet with a drift not linear in p).
#[derive(Clone)]
struct Relativistic;

impl Hamiltonian<nalgebra::U1> for Relativistic {
    const TIME_DEPENDENT: bool = false;
    const STRUCTURE: HamiltonianStructure = HamiltonianStructure::Separable;
    fn hamiltonian<D: Scalar>(&self, _t: D, q: &SVector<D, 1>, p: &SVector<D, 1>) -> D {
        (p[0] * p[0] + 1.0).sqrt() + q[0] * q[0] * 0.5
    }
}

/// The methods on Hamilton's equations: on a model written as H (explicit), on constant-mass
/// and general models written as L (the Legendre map, Newton), forced or not.
#[test]
fn hamiltonian_methods_do_not_allocate_per_step() {
    let methods = || {
        [
            AnyMethod::from(Partitioned::symplectic_euler()),
            Partitioned::adjoint_symplectic_euler().into(),
            Partitioned::stormer_verlet().into(),
            ImplicitMidpoint::default().into(),
            Composition::hamiltonian(Scheme::Yoshida4).into(),
            HamiltonianGalerkin::new(4).with_quadrature(3).into(),
            HamiltonianCollocation::new(4).into(),
        ]
    };
    for method in methods() {
        let (q, v) = (SVector::from([1.0]), SVector::from([0.2]));
        assert_loop_allocates_nothing(Canonical::new(Relativistic), method.clone(), q, v);
        assert_loop_allocates_nothing(DampedPendulum::default(), method.clone(), q, v);
        let (q, v) = (SVector::from([0.5, 0.0]), SVector::from([0.0, 3f64.sqrt()]));
        assert_loop_allocates_nothing(Kepler::default(), method.clone(), q, v);
        let (q, v) = (SVector::from([1.0, 0.5]), SVector::from([0.0, 0.0]));
        assert_loop_allocates_nothing(DoublePendulum::default(), method, q, v);
    }
}

#[test]
fn multiscale_does_not_allocate_per_step() {
    // k = 10⁸: ω = 10⁴, so the steps of 0.01 span 16 fast periods (the method's regime).
    let model = SpringPendulum {
        k: 1e8,
        ..SpringPendulum::default()
    };
    let (q, v) = (SVector::from([0.0, 0.5]), SVector::from([0.0, 0.0]));
    assert_loop_allocates_nothing(model, Multiscale::default(), q, v);
}

/// Allocations of a run of `steps` steps of size 0.01 of a runtime-dimension model from
/// its default state, observing the energy at every step.
fn local_allocations<L, M>(model: &L, method: &M, steps: usize) -> usize
where
    L: svi::model::local::LocalDefaults + Clone,
    M: svi::Method<svi::Dyn> + Clone,
{
    let (t0, q, v) = model.initial_state();
    let integrator = Integrator::new(svi::model::local::Terms(model.clone()), method.clone());
    let mut energy = svi::observer::EnergyError::default();
    let before = allocations::count();
    integrator
        .run(
            t0,
            svi::Initial::Velocity { q, v },
            0.01,
            t0 + 0.01 * steps as f64,
            &mut energy,
        )
        .unwrap();
    allocations::count() - before
}

/// The runtime-dimension paths (Verlet, SVI's fixed point, sparse Newton) allocate nothing
/// per step either, with an observer at every step: each observed point reuses the last
/// one's vectors.
#[test]
fn runtime_dimension_paths_do_not_allocate_per_step_or_per_observed_point() {
    use svi::model::local::LocalDefaults;
    use svi_models::{Fput, RelativisticChain};
    let mut fput = Fput::default();
    fput.set_parameter("n", 64.0).unwrap();
    let mut relativistic = RelativisticChain::default();
    relativistic.set_parameter("n", 16.0).unwrap();
    let verlet = StormerVerlet::default();
    let svi = Svi::new(6).with_quadrature(5);
    assert_eq!(
        local_allocations(&fput, &verlet, 20),
        local_allocations(&fput, &verlet, 2000),
        "verlet"
    );
    let euler = VariationalIntegrator::new(SymplecticEuler);
    assert_eq!(
        local_allocations(&fput, &euler, 20),
        local_allocations(&fput, &euler, 2000),
        "symplectic euler"
    );
    assert_eq!(
        local_allocations(&fput, &svi, 20),
        local_allocations(&fput, &svi, 2000),
        "svi, fixed point"
    );
    let svi = Svi::new(4).with_quadrature(3);
    assert_eq!(
        local_allocations(&relativistic, &svi, 20),
        local_allocations(&relativistic, &svi, 200),
        "svi, sparse Newton"
    );
}

/// A run-time-size N-body run allocates nothing per step, observed or not: its derivatives
/// are taken pair term by pair term on the stack (before `NBody` was a sum of pair terms,
/// its n scalar sweeps made dual-number vectors, three per step), and the Noether momenta
/// and the energy observed at every step add none (each momentum is p·ξᵢ(q) body by body,
/// [`svi::Symmetries::generator_momentum`]; before, one vector ξᵢ per generator and step).
#[test]
fn observed_momenta_of_a_run_time_size_model_add_no_allocation_per_step() {
    let model = svi_models::NBody::outer_solar_system();
    let (t0, q, v) = svi::Defaults::initial_state(&model);
    let integrator = Integrator::new(model, StormerVerlet::default());
    let run = |steps: usize, observed: bool| {
        let mut observers = (
            svi::observer::MomentumError::default(),
            svi::observer::EnergyError::default(),
        );
        let start = svi::Initial::Velocity {
            q: q.clone(),
            v: v.clone(),
        };
        let t_end = t0 + 10.0 * steps as f64;
        let before = allocations::count();
        if observed {
            integrator.run(t0, start, 10.0, t_end, &mut observers)
        } else {
            integrator.run(t0, start, 10.0, t_end, &mut ())
        }
        .unwrap();
        let count = allocations::count() - before;
        if observed {
            assert!(observers.0.max > 0.0 && observers.1.max > 0.0);
        }
        count
    };
    run(5, true);
    let per_steps = |observed: bool| run(2000, observed) - run(20, observed);
    assert_eq!(per_steps(false), 0);
    assert_eq!(per_steps(true), 0);
}

/// Allocations of an unobserved run of `steps` steps of size 0.01 of a sum of local terms from
/// its default state, by the one implementation of ℝᴺ (`Terms`).
fn terms_allocations<L, M>(model: &L, method: &M, steps: usize) -> usize
where
    L: svi::model::local::LocalDefaults + Clone,
    M: svi::Method<svi::Dyn> + Clone,
{
    let (t0, q, v) = model.initial_state();
    let integrator = Integrator::new(svi::model::local::Terms(model.clone()), method.clone());
    let before = allocations::count();
    integrator
        .run_from_velocity(t0, q, v, 0.01, t0 + 0.01 * steps as f64, &mut ())
        .unwrap();
    allocations::count() - before
}

/// The one implementation of ℝᴺ runs a sum of local terms of run-time size without
/// allocating per step: Verlet, SVI's fixed point, SVI and midpoint by sparse Newton, and the
/// reference methods (the stepping loop's checked compensated sum included).
#[test]
fn sums_of_terms_do_not_allocate_per_step() {
    use svi::method::reference::{ExplicitEuler, ImplicitEuler, RungeKutta4};
    use svi::model::local::LocalDefaults;
    use svi_models::{Fput, RelativisticChain};
    let mut fput = Fput::default();
    fput.set_parameter("n", 64.0).unwrap();
    let mut relativistic = RelativisticChain::default();
    relativistic.set_parameter("n", 16.0).unwrap();
    let verlet = StormerVerlet::default();
    assert_eq!(
        terms_allocations(&fput, &verlet, 20),
        terms_allocations(&fput, &verlet, 2000),
        "verlet"
    );
    let svi = Svi::new(6).with_quadrature(5);
    assert_eq!(
        terms_allocations(&fput, &svi, 20),
        terms_allocations(&fput, &svi, 2000),
        "svi, fixed point"
    );
    let svi = Svi::new(4).with_quadrature(3);
    assert_eq!(
        terms_allocations(&relativistic, &svi, 20),
        terms_allocations(&relativistic, &svi, 200),
        "svi, sparse Newton"
    );
    let midpoint = VariationalIntegrator::new(Midpoint);
    assert_eq!(
        terms_allocations(&relativistic, &midpoint, 20),
        terms_allocations(&relativistic, &midpoint, 200),
        "midpoint, sparse Newton"
    );
    // The non-symplectic references: RK4's stages live in its workspace, implicit Euler
    // solves in the increment.
    assert_eq!(
        terms_allocations(&fput, &RungeKutta4, 20),
        terms_allocations(&fput, &RungeKutta4, 2000),
        "rk4"
    );
    assert_eq!(
        terms_allocations(&fput, &ExplicitEuler, 20),
        terms_allocations(&fput, &ExplicitEuler, 2000),
        "explicit euler"
    );
    let implicit = ImplicitEuler::default();
    assert_eq!(
        terms_allocations(&relativistic, &implicit, 20),
        terms_allocations(&relativistic, &implicit, 200),
        "implicit euler, sparse Newton"
    );
}
