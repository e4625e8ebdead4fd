//! The zoo's models written as Hamiltonians: each against its Lagrangian twin (the same
//! trajectory under SVI, the same exact solution and defaults), and the magnetic bottle
//! against its field's identities, a Runge–Kutta integration of the Lorentz force written
//! here, and the adiabatic theory of the magnetic mirror.

use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, SVector, U3};
use num_dual::Dual64;
use svi::method::PhasePoint;
use svi::model::hamiltonian::{
    HamiltonianDefaults, HamiltonianExactSolution, HamiltonianInvariants,
};
use svi::observer::{EnergyError, MomentumError, Trajectory};
use svi::{Canonical, Defaults, Dimension, Error, ExactSolution, Integrator, Lagrangian, Svi};
use svi_models::{HenonHeiles, HenonHeilesH, Kepler, KeplerH, MagneticBottle, Pendulum, PendulumH};

/// SVI with 7 CGL points and 6 Gauss points (the paper's Kepler setting), `steps` steps of
/// the model's default step from its default state; the last point.
fn run_svi<M: Lagrangian<N> + Defaults<N>, N: Dimension>(model: M, steps: usize) -> PhasePoint<N>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    let (t0, q0, v0) = model.initial_state();
    let h = model.default_step();
    let integrator = Integrator::new(model, Svi::new(7).with_quadrature(6));
    integrator
        .run_from_velocity(t0, q0, v0, h, t0 + steps as f64 * h, &mut ())
        .unwrap()
        .last
}

/// The largest difference between two points' q, q̇ and p.
fn difference<N: Dimension>(a: &PhasePoint<N>, b: &PhasePoint<N>) -> f64
where
    DefaultAllocator: Allocator<N>,
{
    assert_eq!(a.t, b.t);
    [
        (&a.q - &b.q).amax(),
        (&a.v - &b.v).amax(),
        (&a.p - &b.p).amax(),
    ]
    .into_iter()
    .fold(0.0, f64::max)
}

/// Checks that the Hamiltonian's defaults are its twin's, read in (q, q̇).
fn same_defaults<L: Defaults<N>, H: Defaults<N>, N: Dimension>(twin: &L, model: &H)
where
    DefaultAllocator: Allocator<N>,
{
    assert_eq!(model.parameters(), twin.parameters());
    assert_eq!(model.coordinate_names(), twin.coordinate_names());
    assert_eq!(model.default_step(), twin.default_step());
    assert_eq!(model.default_horizon(), twin.default_horizon());
    let (a, b) = (model.initial_state(), twin.initial_state());
    assert_eq!(a.0, b.0);
    assert_eq!(a.1, b.1);
    assert!((&a.2 - &b.2).amax() < 1e-15, "{} {}", a.2, b.2);
}

#[test]
fn kepler_h_runs_as_kepler() {
    let (twin, model) = (Kepler::default(), Canonical::new(KeplerH::default()));
    same_defaults(&twin, &model);
    // 1000 steps of h = 0.2: about 32 orbits of e = 0.5.
    let gap = difference(&run_svi(twin, 1000), &run_svi(model.clone(), 1000));
    // Measured: 0, bit for bit (Canonical of a quadratic H is ½ q̇ᵀMq̇ − V with M = 1).
    assert!(gap < 1e-12, "kepler against kepler-h: {gap:e}");
    // The exact solutions agree, in (q, q̇) and in (q, p).
    let (t0, q0, v0) = twin.initial_state();
    for t in [0.3, 17.0, 1999.9] {
        let (q, v) = twin.exact_solution(t0, &q0, &v0, t).unwrap();
        let (qh, vh) = model.exact_solution(t0, &q0, &v0, t).unwrap();
        let (qp, p) = KeplerH::default().exact_solution(t0, &q0, &v0, t).unwrap();
        assert!(
            (q - qh).amax() < 1e-15 && (v - vh).amax() < 1e-15,
            "t = {t}"
        );
        assert_eq!((qp, p), (q, v));
    }
    // Its invariants (Runge–Lenz) are Kepler's: |A| = e.
    let runge_lenz = KeplerH::default().invariant(0, 0.0, &q0, &v0);
    assert!((runge_lenz - 0.5).abs() < 1e-15, "{runge_lenz}");
}

#[test]
fn pendulum_h_runs_as_the_pendulum() {
    // Parameters away from 1, so that p = m l² θ̇ ≠ θ̇ is tested; θ̇₀ ≠ 0 through the
    // exact solution below.
    let mut twin = Pendulum::default();
    let mut model = Canonical::new(PendulumH::default());
    for (name, value) in [("m", 2.0), ("l", 0.5), ("g", 3.0)] {
        twin.set_parameter(name, value).unwrap();
        model.set_parameter(name, value).unwrap();
    }
    same_defaults(&twin, &model);
    // The default horizon: 1000 steps of h = 0.1.
    let gap = difference(&run_svi(twin, 1000), &run_svi(model.clone(), 1000));
    // Measured: 0.
    assert!(gap < 1e-12, "pendulum against pendulum-h: {gap:e}");
    // Libration and rotation: the same exact solution; p = m l² θ̇ = 0.5 θ̇.
    for (theta0, rate0) in [(1.0, 0.3), (0.2, 9.0)] {
        let (q0, v0) = (SVector::from([theta0]), SVector::from([rate0]));
        for t in [0.7, 35.0] {
            let (q, v) = twin.exact_solution(0.0, &q0, &v0, t).unwrap();
            let (qh, vh) = model.exact_solution(0.0, &q0, &v0, t).unwrap();
            assert!(
                (q - qh).amax() < 1e-14 && (v - vh).amax() < 1e-14,
                "t = {t}"
            );
            let (_, p) = model
                .hamiltonian()
                .exact_solution(0.0, &q0, &(v0 * 0.5), t)
                .unwrap();
            assert!((p - v * 0.5).amax() < 1e-14);
        }
    }
}

#[test]
fn henon_heiles_h_runs_as_henon_heiles() {
    let (twin, model) = (
        HenonHeiles::default(),
        Canonical::new(HenonHeilesH::default()),
    );
    same_defaults(&twin, &model);
    // 1000 steps of h = 0.1 in the chaotic sea (Lyapunov exponent about 0.05: round-off
    // grows by about e⁵ over T = 100).
    let gap = difference(&run_svi(twin, 1000), &run_svi(model.clone(), 1000));
    // Measured: 0.
    assert!(gap < 1e-12, "henon-heiles against henon-heiles-h: {gap:e}");
    let (t0, q0, v0) = model.initial_state();
    assert_eq!(model.exact_solution(t0, &q0, &v0, 1.0), None);
}

/// The name of the parameter an `InvalidParameter` error is about, and its reason.
fn invalid(result: Result<(), Error>) -> (String, String) {
    match result {
        Err(Error::InvalidParameter { name, reason }) => (name, reason),
        other => panic!("expected an invalid parameter, got {other:?}"),
    }
}

#[test]
fn bad_parameters_are_invalid_parameters_named_after_the_model() {
    let mut kepler = KeplerH::default();
    let (name, reason) = invalid(kepler.set_parameter("mu", 1.0));
    assert_eq!(name, "mu");
    assert!(
        reason.contains("'kepler-h'") && reason.contains("known: e"),
        "{reason}"
    );
    for e in [1.0, 1.5, -0.1, f64::NAN] {
        assert_eq!(invalid(kepler.set_parameter("e", e)).0, "e");
    }
    assert_eq!(kepler, KeplerH::default());
    let mut pendulum = PendulumH::default();
    assert_eq!(invalid(pendulum.set_parameter("m", -1.0)).0, "m");
    assert_eq!(invalid(pendulum.set_parameter("l", 0.0)).0, "l");
    let (_, reason) = invalid(pendulum.set_parameter("theta", 1.0));
    assert!(reason.contains("'pendulum-h'"), "{reason}");
    let mut henon_heiles = HenonHeilesH::default();
    assert_eq!(
        invalid(henon_heiles.set_parameter("energy", 0.01)).0,
        "energy"
    );
    assert_eq!(
        invalid(henon_heiles.set_parameter("lambda", -1.0)).0,
        "lambda"
    );
    let mut bottle = MagneticBottle::default();
    for name in MagneticBottle::PARAMETERS {
        for bad in [-1.0, 0.0, f64::INFINITY] {
            assert_eq!(invalid(bottle.set_parameter(name, bad)).0, name);
        }
    }
    assert_eq!(bottle, MagneticBottle::default());
    let (_, reason) = invalid(bottle.set_parameter("q", 1.0));
    assert!(reason.contains("'magnetic-bottle'"), "{reason}");
    // Through the adapter, as the registry hands them out.
    let mut canonical = Canonical::new(MagneticBottle::default());
    assert_eq!(invalid(canonical.set_parameter("m", -2.0)).0, "m");
    canonical.set_parameter("m", 2.0).unwrap();
    assert_eq!(canonical.hamiltonian().m, 2.0);
}

// ----- the magnetic bottle -----

/// ∂F/∂xⱼ of a field F: ℝ³ → ℝ³ at x by forward-mode AD, entry (i, j) = ∂Fᵢ/∂xⱼ.
fn jacobian(
    field: impl Fn(&SVector<Dual64, 3>) -> SVector<Dual64, 3>,
    x: &SVector<f64, 3>,
) -> [[f64; 3]; 3] {
    let mut out = [[0.0; 3]; 3];
    for j in 0..3 {
        let seeded = SVector::from_fn(|i, _| Dual64::new(x[i], if i == j { 1.0 } else { 0.0 }));
        let value = field(&seeded);
        for (i, row) in out.iter_mut().enumerate() {
            row[j] = value[i].eps;
        }
    }
    out
}

#[test]
fn the_bottle_field_is_the_curl_of_its_potential_and_divergence_free() {
    let mut bottle = MagneticBottle::default();
    bottle.set_parameter("b0", 1.7).unwrap();
    bottle.set_parameter("l", 3.0).unwrap();
    for x in [
        [0.3, -1.2, 0.8],
        [2.0, 0.5, -4.0],
        [0.0, 0.0, 1.0],
        [-1.5, 2.5, 0.0],
    ] {
        let x = SVector::from(x);
        let a = jacobian(|x| bottle.vector_potential(x), &x);
        let curl = SVector::from([a[2][1] - a[1][2], a[0][2] - a[2][0], a[1][0] - a[0][1]]);
        let field = bottle.magnetic_field(&x);
        assert!(
            (curl - field).amax() < 1e-14,
            "{x}: curl A = {curl}, B = {field}"
        );
        let b = jacobian(|x| bottle.magnetic_field(x), &x);
        let divergence = b[0][0] + b[1][1] + b[2][2];
        assert!(divergence.abs() < 1e-15, "{x}: div B = {divergence:e}");
        // On the axis B = B₀(1 + z²/L²) ẑ.
        let axis = bottle.magnetic_field(&SVector::from([0.0, 0.0, x[2]]));
        let expected = 1.7 * (1.0 + x[2] * x[2] / 9.0);
        assert!(axis[0] == 0.0 && axis[1] == 0.0 && (axis[2] - expected).abs() < 1e-15);
    }
}

/// Classical RK4 on the Lorentz force m v̇ = e v × B, `steps` steps of size `h`.
fn lorentz_rk4(
    bottle: &MagneticBottle,
    mut x: SVector<f64, 3>,
    mut v: SVector<f64, 3>,
    h: f64,
    steps: usize,
) -> (SVector<f64, 3>, SVector<f64, 3>) {
    let force = |x: &SVector<f64, 3>, v: &SVector<f64, 3>| {
        v.cross(&bottle.magnetic_field(x)) * (bottle.charge / bottle.m)
    };
    for _ in 0..steps {
        let (k1x, k1v) = (v, force(&x, &v));
        let (x2, v2) = (x + k1x * (0.5 * h), v + k1v * (0.5 * h));
        let (k2x, k2v) = (v2, force(&x2, &v2));
        let (x3, v3) = (x + k2x * (0.5 * h), v + k2v * (0.5 * h));
        let (k3x, k3v) = (v3, force(&x3, &v3));
        let (x4, v4) = (x + k3x * h, v + k3v * h);
        let (k4x, k4v) = (v4, force(&x4, &v4));
        x += (k1x + k2x * 2.0 + k3x * 2.0 + k4x) * (h / 6.0);
        v += (k1v + k2v * 2.0 + k3v * 2.0 + k4v) * (h / 6.0);
    }
    (x, v)
}

#[test]
fn the_bottle_hamiltonian_moves_the_particle_by_the_lorentz_force() {
    // Half a bounce (T ≈ 126, 20 gyrations), SVI 7/6 at the default step against RK4 with a
    // step 256 times smaller: their gap falls 16-fold per halving of RK4's step, 1.8e-7 at
    // h/16, 2.8e-11 at h/128, 1.8e-12 at h/256 (RK4's error; SVI's is below).
    let bottle = MagneticBottle::default();
    let model = Canonical::new(bottle);
    let (_, x0, v0) = model.initial_state();
    let steps = 640;
    let last = run_svi(model.clone(), steps);
    let h = model.default_step();
    let (x, v) = lorentz_rk4(&bottle, x0, v0, h / 256.0, 256 * steps);
    let (dx, dv) = ((last.q - x).amax(), (last.v - v).amax());
    assert!(dx < 1e-11 && dv < 1e-11, "against RK4: x {dx:e}, v {dv:e}");
    // The canonical momentum is m v + eA.
    assert!((last.p - bottle.momentum(&last.q, &last.v)).amax() < 1e-14);
}

/// μ over the points of a run.
fn magnetic_moments(bottle: &MagneticBottle, points: &[PhasePoint<U3>]) -> Vec<f64> {
    points
        .iter()
        .map(|point| bottle.invariant(0, point.t, &point.q, &point.p))
        .collect()
}

#[test]
fn the_bottle_traps_the_particle_and_conserves_energy_p_phi_and_mu() {
    // The default run: 10 bounce periods (T ≈ 2513, 12 800 steps, 400 gyrations).
    let bottle = MagneticBottle::default();
    let model = Canonical::new(bottle);
    let (t0, x0, v0) = model.initial_state();
    let (h, horizon) = (model.default_step(), model.default_horizon());
    let integrator = Integrator::new(model, Svi::new(7).with_quadrature(6));
    let mut observers = (
        EnergyError::default(),
        MomentumError::default(),
        Trajectory::new(),
    );
    integrator
        .run_from_velocity(t0, x0, v0, h, t0 + horizon, &mut observers)
        .unwrap();
    let (energy, momentum, trajectory) = observers;
    let points = &trajectory.points;
    let energy0 = energy.initial.unwrap();
    // E = ½ m |v|² = ½ (0.25² + 0.25²).
    assert!((energy0 - 0.0625).abs() < 1e-16);
    let energy_error = energy.max / energy0;
    // Measured: 2.4e-13 and 9.8e-15.
    assert!(
        energy_error < 1e-11,
        "relative energy error {energy_error:e}"
    );
    // p_φ = m x v_y + e r A_φ = 2.5 · 0.25 + 2.5²/2 at the start, kept to round-off.
    assert!((momentum.initial[0] - (0.625 + 3.125)).abs() < 1e-14);
    assert!(momentum.max < 1e-13, "p_phi error {:e}", momentum.max);

    // μ: O(ε) oscillations about its initial value, no drift from the first bounce to the
    // last one.
    let moments = magnetic_moments(&bottle, points);
    let mu0 = moments[0];
    assert!((mu0 - 0.5 * 0.25 * 0.25).abs() < 1e-16);
    let band = moments
        .iter()
        .map(|mu| (mu - mu0).abs() / mu0)
        .fold(0.0, f64::max);
    assert!(band < 0.04, "μ varies by {band:e} of μ₀");
    let per_bounce = (bottle.bounce_period() / h).round() as usize;
    let mean = |range: &[f64]| range.iter().sum::<f64>() / range.len() as f64;
    let (first, last) = (
        mean(&moments[..per_bounce]),
        mean(&moments[moments.len() - per_bounce..]),
    );
    let drift = (last - first).abs() / mu0;
    // Measured: a band of 2.8e-2 (ε = 2.5e-2), a drift of 6.3e-5.
    assert!(drift < 5e-4, "μ drifts by {drift:e} of μ₀ in 9 bounces");

    // Trapped: the guiding centre turns near the mirror points |B| = 2B₀, z ≈ ±L, and
    // crosses z = 0 twice per bounce period 2πL/v_⊥₀ (adiabatic theory, to O(ε)).
    let l = bottle.l;
    let highest = points.iter().map(|p| p.q[2].abs()).fold(0.0, f64::max);
    assert!(
        highest > 0.95 * l && highest < 1.01 * l,
        "highest |z| = {highest}, mirror points at ±{l}"
    );
    let crossings: Vec<f64> = points
        .windows(2)
        .filter(|pair| pair[0].q[2] * pair[1].q[2] < 0.0)
        .map(|pair| pair[1].t)
        .collect();
    // 10 bounce periods from z = 0: a crossing every half period, the last one near the end.
    let count = crossings.len();
    assert!(count == 19 || count == 20, "{crossings:?}");
    let half_bounce = (crossings[count - 1] - crossings[0]) / (count - 1) as f64;
    let theory = 0.5 * bottle.bounce_period();
    // Measured: highest |z| = 9.83 (off the axis the field lines fan out, so |B| = 2B₀ comes
    // a little below z = L), 20 crossings, half bounce 125.10 against 125.66.
    assert!(
        (half_bounce / theory - 1.0).abs() < 0.02,
        "half bounce {half_bounce}, adiabatic theory {theory}"
    );
}

#[test]
fn the_relativistic_chain_as_h_by_the_explicit_splitting_matches_the_lagrangian_svi() {
    // n = 64 from the Lagrangian's default state (peak speed 0.8 c, γ up to 1.67), T = 10:
    // kahan-li8-h on H, explicit (no Newton iteration, no Hessian), against SVI 7/6 with
    // sparse Newton on L. Both are accurate to about 1e-10 at these steps.
    use svi::model::local::Terms;
    use svi::model::local_hamiltonian::LocalCanonical;
    use svi::{Initial, MethodSpec};
    use svi_models::{RelativisticChain, RelativisticChainH};

    let chain = RelativisticChain {
        n: 64,
        ..RelativisticChain::default()
    };
    let hamiltonian = RelativisticChainH(chain.clone());
    let (t0, q0, p0) = hamiltonian.initial_state();
    let (_, _, v0) = svi::model::local::LocalDefaults::initial_state(&chain);
    let t_end = 10.0;
    let lagrangian = Integrator::new(Terms(chain.clone()), Svi::new(7).with_quadrature(6))
        .run_from_velocity(t0, q0.clone(), v0, 0.05, t_end, &mut ())
        .unwrap();
    let splitting = "kahan-li8-h"
        .parse::<MethodSpec>()
        .unwrap()
        .vector_method()
        .unwrap();
    let mut energy = EnergyError::default();
    let explicit = Integrator::new(LocalCanonical::new(hamiltonian.clone()), splitting)
        .run(
            t0,
            Initial::Momentum {
                q: q0.clone(),
                p: p0.clone(),
            },
            0.02,
            t_end,
            &mut energy,
        )
        .unwrap();
    assert_eq!(
        explicit.statistics.iterations, 0,
        "the splitting is explicit"
    );
    let gap = (&explicit.last.q - &lagrangian.last.q)
        .amax()
        .max((&explicit.last.p - &lagrangian.last.p).amax());
    eprintln!(
        "relativistic chain n = 64: explicit kahan-li8-h against svi:7/6, {gap:.2e}; energy error {:.2e}",
        energy.max
    );
    assert!(gap < 1e-8, "{gap:e}");
    assert!(energy.max < 1e-9, "{:e}", energy.max);
    // verlet-h: second order, explicit.
    let verlet = "verlet-h"
        .parse::<MethodSpec>()
        .unwrap()
        .vector_method()
        .unwrap();
    let gaps: Vec<f64> = [0.02, 0.01]
        .iter()
        .map(|&h| {
            let run = Integrator::new(LocalCanonical::new(hamiltonian.clone()), verlet.clone())
                .run(
                    t0,
                    Initial::Momentum {
                        q: q0.clone(),
                        p: p0.clone(),
                    },
                    h,
                    t_end,
                    &mut (),
                )
                .unwrap();
            (&run.last.q - &lagrangian.last.q).amax()
        })
        .collect();
    let order = (gaps[0] / gaps[1]).log2();
    eprintln!("verlet-h against svi:7/6: {gaps:?}, order {order:.2}");
    assert!((order - 2.0).abs() < 0.1, "{order}");
    // A Lagrangian method refuses the model, naming why.
    let error = Integrator::new(LocalCanonical::new(hamiltonian), Svi::default())
        .run(t0, Initial::Momentum { q: q0, p: p0 }, 0.05, 1.0, &mut ())
        .unwrap_err();
    assert!(error.to_string().contains("no Lagrangian"), "{error}");
}
