//! The multisymplectic integrator of `svi::field` on the field models of the zoo, against
//! their exact solutions (d'Alembert, the sine-Gordon kink and breather, the φ⁴ kink): order
//! 2, the discrete multisymplectic conservation law, bounded energy, explicit against
//! Newton, and the typed errors of bad input.

use crate::allocations;

use nalgebra::SVector;
use svi::Error;
use svi::Scalar;
use svi::drift::EnergyWindows;
use svi::field::mesh::Mesh;
use svi::field::multisymplectic::{
    CellQuadrature, FieldRun, Multisymplectic, MultisymplecticOptions,
};
use svi::model::density::{
    Boundary, DensityStructure, Domain, ExactField, FieldDefaults, LagrangianDensity,
};
use svi::verify::observed_order;
use svi_models::{Phi4Kink, SineGordonBreather, SineGordonKink, Wave};

/// Run `model` from its initial field on `points` nodes with step `dt` for `levels` levels;
/// returns the run and the largest |u − u_exact| over all nodes and levels.
fn run_against_exact<F: FieldDefaults<1> + ExactField<1> + Clone>(
    model: &F,
    points: usize,
    dt: f64,
    levels: usize,
    options: MultisymplecticOptions,
) -> Result<(FieldRun<1>, f64), Error> {
    let mesh = Mesh::new(model.domain(), points, dt, model.boundary())?;
    let xs: Vec<f64> = (0..points).map(|n| mesh.x(n)).collect();
    let integrator = Multisymplectic::new(model.clone(), mesh, options)?;
    let mut error = 0.0f64;
    let run = integrator.run(
        0.0,
        |x| model.initial_field(x),
        levels,
        |_, t, u: &[SVector<f64, 1>]| {
            for (x, value) in xs.iter().zip(u) {
                error = error.max((value[0] - model.exact_field(*x, t)[0]).abs());
            }
        },
    )?;
    Ok((run, error))
}

fn options(quadrature: CellQuadrature) -> MultisymplecticOptions {
    let mut options = MultisymplecticOptions::default();
    options.quadrature = quadrature;
    options
}

#[test]
fn the_wave_equation_converges_at_order_two_against_dalembert() {
    // Periodic on [0, 2π]: Δx = 2π/M, Δt = Δx/2 (c = 1), up to t = π/2.
    let wave = Wave::default();
    let mut steps = Vec::new();
    let mut errors = Vec::new();
    for points in [32, 64, 128] {
        let dx = 2.0 * std::f64::consts::PI / points as f64;
        let (run, error) = run_against_exact(
            &wave,
            points,
            0.5 * dx,
            points / 2,
            options(CellQuadrature::Trapezoid),
        )
        .unwrap();
        assert!(run.explicit);
        steps.push(dx);
        errors.push(error);
    }
    let order = observed_order(&steps, &errors, 1e-13).unwrap();
    eprintln!("wave (trapezoid, Δt = Δx/2): errors {errors:?}, order {order:.3}");
    assert!((order - 2.0).abs() < 0.2, "{order} from {errors:?}");
    assert!(errors[2] < 2e-3, "{errors:?}");
    // At Δt = Δx/c the leapfrog scheme is exact on the grid for the wave equation.
    let (_, error) = run_against_exact(
        &wave,
        64,
        2.0 * std::f64::consts::PI / 64.0,
        64,
        options(CellQuadrature::Trapezoid),
    )
    .unwrap();
    assert!(error < 1e-12, "{error}");
}

#[test]
fn the_kinks_converge_at_order_two() {
    // Δx = c Δt with the midpoint (box) scheme, implicit; Δt = Δx/2 with the explicit
    // trapezoidal scheme (Δt = Δx would break its stability limit with the potential).
    let kink = SineGordonKink::default();
    let phi4 = Phi4Kink::default();
    for (quadrature, ratio) in [
        (CellQuadrature::Midpoint, 1.0),
        (CellQuadrature::Trapezoid, 0.5),
    ] {
        for name in ["sine-gordon", "phi4"] {
            let mut steps = Vec::new();
            let mut errors = Vec::new();
            for points in [101, 201, 401] {
                let dx = 40.0 / (points - 1) as f64;
                let dt = ratio * dx;
                let levels = (4.0 / dt).round() as usize;
                let (run, error) = if name == "phi4" {
                    run_against_exact(&phi4, points, dt, levels, options(quadrature)).unwrap()
                } else {
                    run_against_exact(&kink, points, dt, levels, options(quadrature)).unwrap()
                };
                assert_eq!(run.explicit, quadrature == CellQuadrature::Trapezoid);
                steps.push(dx);
                errors.push(error);
            }
            let order = observed_order(&steps, &errors, 1e-13).unwrap();
            eprintln!(
                "{name} kink ({quadrature:?}, Δt = {ratio} Δx): errors {errors:?}, order {order:.3}"
            );
            assert!(
                (order - 2.0).abs() < 0.2,
                "{name} {quadrature:?}: {order} from {errors:?}"
            );
        }
    }
}

#[test]
fn the_breather_keeps_the_multisymplectic_law_to_round_off_over_ten_thousand_levels() {
    // Δx = 0.4, Δt = 0.2: 10⁴ levels are t = 2000, 159 breather periods.
    let breather = SineGordonBreather::default();
    let mut check = options(CellQuadrature::Trapezoid);
    check.multisymplectic_check = true;
    let (run, error) = run_against_exact(&breather, 101, 0.2, 10_000, check).unwrap();
    let residual = run.multisymplectic_residual_max.unwrap();
    eprintln!(
        "breather, trapezoid, 10⁴ levels: multisymplectic residual {residual:.3e}, error {error:.3e}"
    );
    assert!(residual <= 1e-12, "{residual}");
    assert!(residual > 0.0);
    // The implicit midpoint scheme on 500 levels.
    check.quadrature = CellQuadrature::Midpoint;
    let (run, _) = run_against_exact(&breather, 101, 0.2, 500, check).unwrap();
    let residual = run.multisymplectic_residual_max.unwrap();
    eprintln!("breather, midpoint, 500 levels: multisymplectic residual {residual:.3e}");
    assert!(residual <= 1e-12, "{residual}");
}

#[test]
fn the_energy_error_is_bounded_without_drift_over_a_hundred_thousand_levels() {
    // The breather on a coarse mesh (Δx = 0.5, Δt = 0.25): t = 25 000, 2000 periods.
    let breather = SineGordonBreather::default();
    let (run, _) = run_against_exact(
        &breather,
        81,
        0.25,
        100_000,
        options(CellQuadrature::Trapezoid),
    )
    .unwrap();
    let mut windows = EnergyWindows::new(1000);
    for (j, energy) in run.energy.iter().enumerate() {
        windows.push((j as f64 + 0.5) * 0.25, *energy);
    }
    let fit = windows.fit().unwrap();
    eprintln!(
        "breather energy over 10⁵ levels: E₀ = {:.6}, max |E − E₀| = {:.3e}, drift {:.3e}, amplitude {:.3e}",
        run.energy[0], fit.max_error, fit.drift, fit.amplitude
    );
    assert!(!fit.drifts(), "{fit:?}");
    assert!(fit.max_error < 5e-2 * run.energy[0].abs(), "{fit:?}");
}

#[test]
fn energy_and_momentum_of_the_moving_kink_stay_near_their_exact_values() {
    // Exact: E = 8γ, P = 8γv for the sine-Gordon kink.
    let kink = SineGordonKink::default();
    let gamma = 1.0 / (1.0 - kink.speed * kink.speed).sqrt();
    let (run, _) =
        run_against_exact(&kink, 401, 0.05, 200, options(CellQuadrature::Trapezoid)).unwrap();
    for (energy, momentum) in run.energy.iter().zip(&run.momentum) {
        assert!((energy - 8.0 * gamma).abs() < 1e-2, "{energy}");
        assert!(
            (momentum - 8.0 * gamma * kink.speed).abs() < 1e-2,
            "{momentum}"
        );
    }
    let spread = run.energy.iter().fold(f64::NEG_INFINITY, |a, &b| a.max(b))
        - run.energy.iter().fold(f64::INFINITY, |a, &b| a.min(b));
    eprintln!(
        "kink: E = {:.6} (exact {:.6}), spread {spread:.3e}",
        run.energy[0],
        8.0 * gamma
    );
    assert!(spread < 1e-4, "{spread}");
}

#[test]
fn the_explicit_scheme_and_newton_solve_the_same_equations() {
    let kink = Phi4Kink::default();
    let explicit = options(CellQuadrature::Trapezoid);
    let mut newton = explicit;
    newton.force_newton = true;
    let (a, _) = run_against_exact(&kink, 201, 0.1, 300, explicit).unwrap();
    let (b, _) = run_against_exact(&kink, 201, 0.1, 300, newton).unwrap();
    assert!(a.explicit && !b.explicit);
    assert!(b.newton_iterations >= 300);
    let difference = a
        .last
        .iter()
        .zip(&b.last)
        .map(|(x, y)| (x - y).amax())
        .fold(0.0, f64::max);
    assert!(difference < 1e-11, "{difference}");
}

/// The name an error carries, or a panic if there is none.
fn error_name<T: std::fmt::Debug>(result: Result<T, Error>) -> String {
    match result {
        Err(Error::InvalidParameter { name, .. }) => name,
        other => panic!("expected an invalid parameter, got {other:?}"),
    }
}

#[test]
fn a_step_above_the_stability_limit_of_the_explicit_scheme_is_an_error() {
    let wave = Wave { speed: 2.0 };
    let dx = 2.0 * std::f64::consts::PI / 64.0;
    let trapezoid = options(CellQuadrature::Trapezoid);
    // Δt = Δx/c is allowed, 1 % more is not.
    assert!(run_against_exact(&wave, 64, dx / 2.0, 10, trapezoid).is_ok());
    let result = run_against_exact(&wave, 64, 1.01 * dx / 2.0, 10, trapezoid);
    let Err(Error::InvalidParameter { name, reason }) = result else {
        panic!("{result:?}");
    };
    assert_eq!(name, "dt");
    assert!(reason.contains("stability limit"), "{reason}");
    // The implicit box scheme has no such limit.
    assert!(run_against_exact(&wave, 64, 4.0 * dx, 10, options(CellQuadrature::Midpoint)).is_ok());
}

#[test]
fn bad_meshes_initial_fields_and_boundaries_are_named_errors() {
    let kink = SineGordonKink::default();
    let domain = kink.domain();
    let boundary = kink.boundary();
    for points in [0, 1] {
        assert_eq!(
            error_name(Mesh::new(domain, points, 0.1, boundary)),
            "points"
        );
    }
    for dt in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert_eq!(error_name(Mesh::new(domain, 100, dt, boundary)), "dt");
    }
    assert_eq!(error_name(Domain::new(1.0, 1.0)), "domain");
    assert_eq!(error_name(Domain::new(f64::NEG_INFINITY, 1.0)), "domain");
    let nan = Boundary::Dirichlet {
        left: SVector::from([f64::NAN]),
        right: SVector::from([0.0]),
    };
    assert_eq!(
        error_name(Mesh::<1>::new(domain, 100, 0.1, nan)),
        "boundary"
    );

    // A kink held at the wrong values at the ends.
    let wrong = Boundary::Dirichlet {
        left: SVector::from([0.0]),
        right: SVector::from([0.0]),
    };
    let mesh = Mesh::new(domain, 101, 0.1, wrong).unwrap();
    let integrator =
        Multisymplectic::new(kink.clone(), mesh, MultisymplecticOptions::default()).unwrap();
    let result = integrator.run(0.0, |x| kink.initial_field(x), 10, |_, _, _| {});
    assert_eq!(error_name(result), "boundary");
    // A non-finite initial field, and a non-finite start time.
    let mesh = Mesh::new(domain, 101, 0.1, boundary).unwrap();
    let integrator =
        Multisymplectic::new(kink.clone(), mesh, MultisymplecticOptions::default()).unwrap();
    let result = integrator.run(
        0.0,
        |x| (SVector::from([x.ln()]), SVector::zeros()),
        10,
        |_, _, _| {},
    );
    assert_eq!(error_name(result), "initial");
    assert_eq!(
        error_name(integrator.run(f64::NAN, |x| kink.initial_field(x), 1, |_, _, _| {})),
        "t0"
    );
    // Bad options.
    let mut bad = MultisymplecticOptions::default();
    bad.tolerance = 0.0;
    let mesh = Mesh::new(domain, 101, 0.1, boundary).unwrap();
    assert_eq!(
        error_name(Multisymplectic::new(kink, mesh, bad)),
        "tolerance"
    );
}

/// ℒ = ½(1 + u²)u_t² − ½u_x², wrongly declared constant-mass.
struct Liar;

impl LagrangianDensity<1> for Liar {
    const STRUCTURE: DensityStructure = DensityStructure::ConstantMass;
    fn density<D: Scalar>(
        &self,
        _x: f64,
        _t: f64,
        u: &SVector<D, 1>,
        u_t: &SVector<D, 1>,
        u_x: &SVector<D, 1>,
    ) -> D {
        ((u[0] * u[0] + 1.0) * u_t[0] * u_t[0] - u_x[0] * u_x[0]) * 0.5
    }
}

#[test]
fn a_density_that_breaks_its_structure_declaration_is_rejected() {
    let domain = Domain::new(0.0, 1.0).unwrap();
    let mesh = Mesh::new(domain, 20, 0.01, Boundary::Periodic).unwrap();
    let integrator = Multisymplectic::new(Liar, mesh, MultisymplecticOptions::default()).unwrap();
    let result = integrator.run(
        0.0,
        |x| (SVector::from([x.sin()]), SVector::from([1.0])),
        5,
        |_, _, _| {},
    );
    assert_eq!(error_name(result), "structure");
}

/// Two uncoupled fields in one: a sine-Gordon kink in component 0 and a Klein–Gordon field of
/// unit mass in component 1, ℒ = ½|u_t|² − ½|u_x|² − (1 − cos u₀) − ½u₁².
#[derive(Clone)]
struct KinkAndKleinGordon;

impl LagrangianDensity<2> for KinkAndKleinGordon {
    const STRUCTURE: DensityStructure = DensityStructure::ConstantMass;
    fn density<D: Scalar>(
        &self,
        _x: f64,
        _t: f64,
        u: &SVector<D, 2>,
        u_t: &SVector<D, 2>,
        u_x: &SVector<D, 2>,
    ) -> D {
        (u_t.dot(u_t) - u_x.dot(u_x)) * 0.5 - (D::from(1.0) - u[0].cos()) - u[1] * u[1] * 0.5
    }
}

#[test]
fn a_field_of_two_components_runs_each_component_as_its_own_field() {
    // Component 0 must follow the one-component sine-Gordon run exactly (the same cells,
    // the same arithmetic up to the order of sums), component 1 stay a Klein–Gordon field.
    let kink = SineGordonKink::default();
    let (points, dt, levels) = (201, 0.1, 200);
    let (reference, _) = run_against_exact(
        &kink,
        points,
        dt,
        levels,
        options(CellQuadrature::Trapezoid),
    )
    .unwrap();
    let boundary = Boundary::Dirichlet {
        left: SVector::from([0.0, 0.0]),
        right: SVector::from([2.0 * std::f64::consts::PI, 0.0]),
    };
    let initial = |x: f64| {
        let (u, u_t) = kink.initial_field(x);
        (
            SVector::from([u[0], 0.1 * (-x * x).exp()]),
            SVector::from([u_t[0], 0.0]),
        )
    };
    for force_newton in [false, true] {
        let mut options = options(CellQuadrature::Trapezoid);
        options.force_newton = force_newton;
        options.multisymplectic_check = true;
        let mesh = Mesh::new(kink.domain(), points, dt, boundary).unwrap();
        let run = Multisymplectic::new(KinkAndKleinGordon, mesh, options)
            .unwrap()
            .run(0.0, initial, levels, |_, _, _| {})
            .unwrap();
        assert_eq!(run.explicit, !force_newton);
        let difference = run
            .last
            .iter()
            .zip(&reference.last)
            .map(|(u, v)| (u[0] - v[0]).abs())
            .fold(0.0, f64::max);
        assert!(difference < 1e-11, "{difference}");
        // The Klein–Gordon pulse disperses: still there, at most its initial height.
        let pulse = run.last.iter().map(|u| u[1].abs()).fold(0.0, f64::max);
        assert!(pulse > 1e-3 && pulse < 0.1, "{pulse}");
        assert!(run.multisymplectic_residual_max.unwrap() < 1e-13);
    }
}

#[test]
fn the_level_loop_allocates_nothing() {
    // A run of 40 levels makes exactly as many heap allocations as a run of 10: all of them
    // in the set-up (buffers, the pattern, the symbolic analysis), none per level.
    let kink = Phi4Kink::default();
    let count = |options: MultisymplecticOptions, levels: usize| {
        let mesh = Mesh::new(kink.domain(), 101, 0.2, kink.boundary()).unwrap();
        let integrator = Multisymplectic::new(kink.clone(), mesh, options).unwrap();
        let before = allocations::count();
        integrator
            .run(0.0, |x| kink.initial_field(x), levels, |_, _, _| {})
            .unwrap();
        allocations::count() - before
    };
    let mut checked = options(CellQuadrature::Trapezoid);
    checked.multisymplectic_check = true;
    for options in [
        options(CellQuadrature::Trapezoid),
        options(CellQuadrature::Midpoint),
        checked,
    ] {
        assert_eq!(count(options, 10), count(options, 40), "{options:?}");
    }
}

#[test]
fn a_newton_solve_that_does_not_converge_is_a_typed_error_with_its_level() {
    let kink = SineGordonKink::default();
    let mut options = options(CellQuadrature::Midpoint);
    options.max_iterations = 1;
    match run_against_exact(&kink, 101, 0.4, 10, options) {
        Err(Error::NonConvergence {
            step,
            t,
            iterations,
            residual,
        }) => {
            assert_eq!((step, t, iterations), (0, 0.0, 1));
            assert!(residual > 0.0);
        }
        other => panic!("{other:?}"),
    }
    options.max_iterations = 0;
    let mesh = Mesh::new(kink.domain(), 101, 0.4, kink.boundary()).unwrap();
    assert_eq!(
        error_name(Multisymplectic::new(kink, mesh, options)),
        "max_iterations"
    );
}
