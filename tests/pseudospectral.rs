//! The pseudospectral integrators of `svi::field::pseudospectral` on the Schrödinger packet
//! and the NLS soliton of the zoo, against their exact solutions (the periodised free
//! Gaussian; the soliton η sech(η(x − ct)) e^{i(cx + (η² − c²)t/2)}): the norm to round-off,
//! spectral convergence in space, the orders in time (2 for the seed's linear-in-time scheme,
//! 2s for the Galerkin SVI of degree s, 2 for Strang), the equivalence of the Galerkin SVI
//! with Gauss collocation on the discrete action itself, the seed's normalisation multiplier
//! (zero on the linear-in-time levels), no allocation per step, and the
//! typed errors of bad input.

use crate::allocations;

use nalgebra::{DMatrix, DVector, SVector};
use svi::Error;
use svi::field::fourier::{Complex64, Fourier};
use svi::field::pseudospectral::{Pseudospectral, PseudospectralOptions, SpectralRun, TimeScheme};
use svi::model::density::{Boundary, ExactField, FieldDefaults, Jet, LagrangianDensityExt};
use svi::quadrature::GaussLegendre;
use svi::verify::observed_order;
use svi_models::{NlsSoliton, SchrodingerPacket};

/// Options with `scheme`.
fn options(scheme: TimeScheme) -> PseudospectralOptions {
    let mut options = PseudospectralOptions::default();
    options.scheme = scheme;
    options
}

/// Run `model` from its initial field on `modes` nodes with step `h` for `steps` steps; the
/// run and the largest |ψ − ψ_exact| at the last level.
fn run_against_exact<F: FieldDefaults<2> + ExactField<2> + Clone>(
    model: &F,
    modes: usize,
    h: f64,
    steps: usize,
    scheme: TimeScheme,
) -> Result<(SpectralRun, f64), Error> {
    let mut integrator = Pseudospectral::new(
        model.clone(),
        model.domain(),
        model.boundary(),
        modes,
        h,
        options(scheme),
    )?;
    let xs: Vec<f64> = (0..modes).map(|j| integrator.fourier().x(j)).collect();
    let initial: Vec<Complex64> = xs
        .iter()
        .map(|&x| {
            let u = model.initial_field(x).0;
            Complex64::new(u[0], u[1])
        })
        .collect();
    let run = integrator.run(0.0, &initial, steps, |_, _, _| {})?;
    let t = steps as f64 * h;
    let error = xs
        .iter()
        .zip(&run.last)
        .map(|(&x, psi)| {
            let exact = model.exact_field(x, t);
            (psi - Complex64::new(exact[0], exact[1])).norm()
        })
        .fold(0.0, f64::max);
    Ok((run, error))
}

#[test]
fn the_norm_is_conserved_to_round_off_over_ten_thousand_steps() {
    // The seed's scheme (linear in time, Crank–Nicolson per mode) on the free packet and on
    // the NLS soliton, 10⁴ steps each: the pseudospectral VI keeps the norm to 1e-13. Strang
    // (unitary substeps) keeps it to round-off too, a few 1e-13 after 10⁴ steps.
    let linear = TimeScheme::Galerkin { degree: 1 };
    let (run, _) =
        run_against_exact(&SchrodingerPacket::default(), 64, 1e-3, 10_000, linear).unwrap();
    eprintln!("packet, linear in time: {:e}", run.norm_error_max);
    assert!(run.norm_error_max <= 1e-13, "{:e}", run.norm_error_max);
    let (run, error) =
        run_against_exact(&NlsSoliton::default(), 256, 1e-3, 10_000, linear).unwrap();
    eprintln!("soliton, linear in time: {:e}", run.norm_error_max);
    assert!(run.norm_error_max <= 1e-13, "{:e}", run.norm_error_max);
    assert!(error < 1e-5, "{error:e}");
    let (run, _) = run_against_exact(
        &NlsSoliton::default(),
        256,
        1e-3,
        10_000,
        TimeScheme::Strang,
    )
    .unwrap();
    eprintln!("soliton, Strang: {:e}", run.norm_error_max);
    assert!(run.norm_error_max <= 1e-12, "{:e}", run.norm_error_max);
}

#[test]
fn the_packet_converges_spectrally_in_space() {
    // Galerkin degree 6 in time (order 12) with h = 0.005: the time error is far below the
    // spatial one; each 8 added modes divide the error by at least 10 down to 1e-11.
    let packet = SchrodingerPacket::default();
    let mut errors = Vec::new();
    for modes in (16..=56).step_by(8) {
        let (run, error) = run_against_exact(
            &packet,
            modes,
            5e-3,
            200,
            TimeScheme::Galerkin { degree: 6 },
        )
        .unwrap();
        assert!(run.norm_error_max < 1e-13);
        errors.push((modes, error));
    }
    eprintln!("modes, error: {errors:?}");
    for pair in errors.windows(2) {
        let ((_, coarse), (modes, fine)) = (pair[0], pair[1]);
        if coarse > 1e-11 {
            assert!(fine <= coarse / 10.0, "{modes} modes: {errors:?}");
        }
    }
    assert!(errors.last().unwrap().1 < 1e-11, "{errors:?}");
}

/// Errors at T = 1 on the soliton (512 modes: the spatial error is near 1e-13) for a ladder of
/// steps.
fn soliton_errors(scheme: TimeScheme, steps: &[f64]) -> Vec<f64> {
    steps
        .iter()
        .map(|&h| {
            let n = (1.0 / h).round() as usize;
            run_against_exact(&NlsSoliton::default(), 512, h, n, scheme)
                .unwrap()
                .1
        })
        .collect()
}

#[test]
fn the_orders_in_time_are_two_for_the_linear_scheme_and_strang_and_2s_for_the_galerkin_svi() {
    for (scheme, steps) in [
        (TimeScheme::Galerkin { degree: 1 }, vec![0.04, 0.02, 0.01]),
        (TimeScheme::Strang, vec![0.04, 0.02, 0.01]),
        (TimeScheme::Galerkin { degree: 2 }, vec![0.2, 0.1, 0.05]),
        (
            TimeScheme::Galerkin { degree: 3 },
            vec![0.25, 0.125, 0.0625],
        ),
    ] {
        let errors = soliton_errors(scheme, &steps);
        let order = observed_order(&steps, &errors, 1e-11).unwrap();
        let expected = scheme.order() as f64;
        eprintln!("{scheme:?}: order {order:.2}, errors {errors:?}");
        assert!(
            order > expected - 0.3 && order < expected + 0.5,
            "{scheme:?}: order {order}, errors {errors:?}"
        );
    }
}

#[test]
fn the_soliton_at_t_10_matches_the_exact_solution() {
    let (run, error) = run_against_exact(
        &NlsSoliton::default(),
        512,
        0.05,
        200,
        TimeScheme::Galerkin { degree: 3 },
    )
    .unwrap();
    assert!(error < 1e-8, "{error:e}");
    assert!(run.norm_error_max < 1e-13, "{:e}", run.norm_error_max);
    // The Hamiltonian is not a quadratic invariant: bounded, not exact.
    assert!((run.energy_final - run.energy_initial).abs() < 1e-8);
    assert!(run.ffts > 0 && run.iterations >= 200);
}

/// ∂L_d/∂q_i of the Galerkin discrete action L_d = h Σ_m b_m L(q(c_m), q̇(c_m)) of the
/// semi-discrete Lagrangian L = Δx Σ_j ℒ(x_j, u_j, u̇_j, (Du)_j), for the polynomial through
/// `nodes` (values at the CGL times `times` on [0, 1]), straight from the density's gradient.
fn action_gradient(
    density: &NlsSoliton,
    fourier: &mut Fourier,
    h: f64,
    times: &[f64],
    nodes: &[Vec<Complex64>],
) -> Vec<Vec<Complex64>> {
    let s = times.len() - 1;
    let rule = GaussLegendre::new(s).unwrap();
    let lagrange = |i: usize, tau: f64| -> f64 {
        (0..=s)
            .filter(|&k| k != i)
            .map(|k| (tau - times[k]) / (times[i] - times[k]))
            .product()
    };
    let d_lagrange = |i: usize, tau: f64| -> f64 {
        (0..=s)
            .filter(|&m| m != i)
            .map(|m| {
                (0..=s)
                    .filter(|&k| k != i && k != m)
                    .map(|k| (tau - times[k]) / (times[i] - times[k]))
                    .product::<f64>()
                    / (times[i] - times[m])
            })
            .sum()
    };
    let modes = nodes[0].len();
    let dx = fourier.dx();
    let mut gradient = vec![vec![Complex64::default(); modes]; s + 1];
    for (&xg, &wg) in rule.nodes().iter().zip(rule.weights()) {
        let (tau, weight) = (0.5 * (xg + 1.0), 0.5 * wg);
        let value: Vec<Complex64> = (0..modes)
            .map(|j| (0..=s).map(|i| nodes[i][j] * lagrange(i, tau)).sum())
            .collect();
        let velocity: Vec<Complex64> = (0..modes)
            .map(|j| (0..=s).map(|i| nodes[i][j] * d_lagrange(i, tau) / h).sum())
            .collect();
        let mut slope = value.clone();
        fourier.derivative_in_place(&mut slope);
        let mut g_u = vec![Complex64::default(); modes];
        let mut g_t = vec![Complex64::default(); modes];
        let mut g_x = vec![Complex64::default(); modes];
        for j in 0..modes {
            let pair = |z: Complex64| SVector::from([z.re, z.im]);
            let jet = Jet {
                u: pair(value[j]),
                u_t: pair(velocity[j]),
                u_x: pair(slope[j]),
            };
            let g = density.gradient(fourier.x(j), 0.0, &jet);
            g_u[j] = Complex64::new(g.u[0], g.u[1]);
            g_t[j] = Complex64::new(g.u_t[0], g.u_t[1]);
            g_x[j] = Complex64::new(g.u_x[0], g.u_x[1]);
        }
        // ∂L/∂q = Δx (G_u + Dᵀ G_x) = Δx (G_u − D G_x).
        fourier.derivative_in_place(&mut g_x);
        for (i, row) in gradient.iter_mut().enumerate() {
            let (l, dl) = (lagrange(i, tau), d_lagrange(i, tau));
            for j in 0..modes {
                row[j] += (g_u[j] - g_x[j]) * (h * weight * l * dx) + g_t[j] * (weight * dl * dx);
            }
        }
    }
    gradient
}

#[test]
fn galerkin_stationarity_holds_on_the_collocation_step() {
    // Degree 2 (three CGL nodes 0, ½, 1): solve the Galerkin equations ∂L_d/∂q_½ = 0 and
    // −∂L_d/∂q_0 = θ(q_0) by Newton's method (finite-difference Jacobian) on 16 modes, and
    // compare q_1 with the Gauss collocation step of the integrator.
    let model = NlsSoliton {
        amplitude: 1.0,
        speed: 0.5,
        position: 0.0,
    };
    let (modes, h) = (16, 0.3);
    let domain = svi::model::density::Domain::new(-4.0, 4.0).unwrap();
    let mut fourier = Fourier::new(domain, modes).unwrap();
    let initial: Vec<Complex64> = (0..modes)
        .map(|j| {
            let u = model.initial_field(fourier.x(j)).0;
            Complex64::new(u[0], u[1])
        })
        .collect();
    let mut integrator = Pseudospectral::new(
        model.clone(),
        domain,
        Boundary::Periodic,
        modes,
        h,
        options(TimeScheme::Galerkin { degree: 2 }),
    )
    .unwrap();
    let collocation = integrator.run(0.0, &initial, 1, |_, _, _| {}).unwrap().last;

    let times = [0.0, 0.5, 1.0];
    let dx = fourier.dx();
    // θ(q_0) = Δx ∂ℒ/∂u_t = Δx (b, −a), as a complex number Δx(b − ia).
    let theta: Vec<Complex64> = initial
        .iter()
        .map(|z| Complex64::new(z.im, -z.re) * dx)
        .collect();
    let residual = |unknowns: &DVector<f64>, fourier: &mut Fourier| -> DVector<f64> {
        let unpack = |offset: usize| -> Vec<Complex64> {
            (0..modes)
                .map(|j| Complex64::new(unknowns[offset + 2 * j], unknowns[offset + 2 * j + 1]))
                .collect()
        };
        let nodes = vec![initial.clone(), unpack(0), unpack(2 * modes)];
        let g = action_gradient(&model, fourier, h, &times, &nodes);
        let mut out = DVector::zeros(4 * modes);
        for j in 0..modes {
            let left = g[0][j] + theta[j];
            out[2 * j] = g[1][j].re;
            out[2 * j + 1] = g[1][j].im;
            out[2 * modes + 2 * j] = left.re;
            out[2 * modes + 2 * j + 1] = left.im;
        }
        out
    };
    let mut unknowns = DVector::zeros(4 * modes);
    for j in 0..modes {
        for (offset, z) in [(0, initial[j]), (2 * modes, initial[j])] {
            unknowns[offset + 2 * j] = z.re;
            unknowns[offset + 2 * j + 1] = z.im;
        }
    }
    for _ in 0..8 {
        let r = residual(&unknowns, &mut fourier);
        let mut jacobian = DMatrix::zeros(4 * modes, 4 * modes);
        for k in 0..4 * modes {
            let mut shifted = unknowns.clone();
            shifted[k] += 1e-7;
            let column = (residual(&shifted, &mut fourier) - &r) / 1e-7;
            jacobian.set_column(k, &column);
        }
        unknowns -= jacobian.lu().solve(&r).unwrap();
    }
    let gap = (0..modes)
        .map(|j| {
            let galerkin =
                Complex64::new(unknowns[2 * modes + 2 * j], unknowns[2 * modes + 2 * j + 1]);
            (galerkin - collocation[j]).norm()
        })
        .fold(0.0, f64::max);
    assert!(gap < 1e-9, "{gap:e}");
}

#[test]
fn the_seeds_normalisation_multiplier_vanishes_on_the_linear_in_time_scheme() {
    // The seed's discrete action adds λ_l (N − ⟨ψ_l, ψ_l⟩) to the linear-in-time action, and
    // its discrete Euler–Lagrange equation at level l is
    //   D₂L_d(q_{l−1}, q_l) + D₁L_d(q_l, q_{l+1}) − 2λ_l Δx q_l = 0,  ⟨ψ_l, ψ_l⟩ = N.
    // On the levels of the one-step scheme, straight from the density's gradient (midpoint
    // quadrature in time): the least-squares λ_l is zero to round-off, the equation holds
    // without it, and the constraint holds at every level.
    let model = NlsSoliton::default();
    let (modes, h, steps) = (64, 0.02, 40);
    let mut integrator = Pseudospectral::new(
        model.clone(),
        model.domain(),
        model.boundary(),
        modes,
        h,
        options(TimeScheme::Galerkin { degree: 1 }),
    )
    .unwrap();
    let mut fourier = Fourier::new(model.domain(), modes).unwrap();
    let dx = fourier.dx();
    let initial: Vec<Complex64> = (0..modes)
        .map(|j| {
            let u = model.initial_field(fourier.x(j)).0;
            Complex64::new(u[0], u[1])
        })
        .collect();
    let mut levels = Vec::new();
    integrator
        .run(0.0, &initial, steps, |_, _, psi| levels.push(psi.to_vec()))
        .unwrap();
    assert_eq!(levels.len(), steps + 1);
    assert_eq!(levels[0], initial);
    let norm = |psi: &[Complex64]| dx * psi.iter().map(|z| z.norm_sqr()).sum::<f64>();
    // The size of one node's terms in the equation: Δx max |ψ| (the kinetic term θ(q)).
    let scale = dx * levels[0].iter().map(|z| z.norm()).fold(0.0, f64::max);
    let n0 = norm(&levels[0]);
    let times = [0.0, 1.0];
    let (mut multiplier_max, mut residual_max) = (0.0_f64, 0.0_f64);
    for l in 1..steps {
        let before = action_gradient(&model, &mut fourier, h, &times, &levels[l - 1..=l]);
        let after = action_gradient(&model, &mut fourier, h, &times, &levels[l..=l + 1]);
        let del: Vec<Complex64> = (0..modes).map(|j| before[1][j] + after[0][j]).collect();
        // ∇_q (N − ⟨ψ_l, ψ_l⟩) = −2Δx q_l: λ_l by least squares in the real inner product.
        let g: Vec<Complex64> = levels[l].iter().map(|z| -2.0 * dx * z).collect();
        let gg: f64 = g.iter().map(|z| z.norm_sqr()).sum();
        let rg: f64 = del
            .iter()
            .zip(&g)
            .map(|(r, g)| r.re * g.re + r.im * g.im)
            .sum();
        let lambda = -rg / gg;
        multiplier_max = multiplier_max.max(lambda.abs());
        residual_max = residual_max.max(del.iter().map(|z| z.norm()).fold(0.0, f64::max));
        assert!((norm(&levels[l]) - n0).abs() < 1e-13 * n0, "level {l}");
    }
    eprintln!("seed's multiplier: max |λ| {multiplier_max:e}, max DEL residual {residual_max:e}");
    assert!(multiplier_max < 1e-12, "{multiplier_max:e}");
    assert!(
        residual_max < 1e-12 * scale,
        "{residual_max:e} against {scale:e}"
    );
}

#[test]
fn stepping_allocates_nothing() {
    let model = NlsSoliton::default();
    let count = |steps: usize, scheme: TimeScheme| {
        let before = allocations::count();
        run_against_exact(&model, 64, 0.05, steps, scheme).unwrap();
        allocations::count() - before
    };
    for scheme in [TimeScheme::Galerkin { degree: 3 }, TimeScheme::Strang] {
        assert_eq!(count(2, scheme), count(40, scheme), "{scheme:?}");
    }
}

#[test]
fn bad_input_is_a_typed_error() {
    let model = NlsSoliton::default();
    let name = |result: Result<Pseudospectral<NlsSoliton>, Error>| match result {
        Err(Error::InvalidParameter { name, .. }) => name,
        other => panic!("{other:?}"),
    };
    let make = |modes: usize, h: f64, boundary: Boundary<2>, scheme: TimeScheme| {
        Pseudospectral::new(
            model.clone(),
            model.domain(),
            boundary,
            modes,
            h,
            options(scheme),
        )
    };
    let gauss = TimeScheme::Galerkin { degree: 2 };
    assert_eq!(name(make(63, 0.01, Boundary::Periodic, gauss)), "modes");
    assert_eq!(name(make(2, 0.01, Boundary::Periodic, gauss)), "modes");
    assert_eq!(name(make(64, 0.0, Boundary::Periodic, gauss)), "h");
    assert_eq!(name(make(64, f64::NAN, Boundary::Periodic, gauss)), "h");
    assert_eq!(
        name(make(
            64,
            0.01,
            Boundary::Periodic,
            TimeScheme::Galerkin { degree: 0 }
        )),
        "degree"
    );
    let dirichlet = Boundary::Dirichlet {
        left: SVector::zeros(),
        right: SVector::zeros(),
    };
    assert_eq!(name(make(64, 0.01, dirichlet, gauss)), "boundary");
    // A step beyond the convergence limit of the stage iteration (ν = η² = 1: h < 2/3).
    match run_against_exact(&model, 64, 1.0, 1, gauss) {
        Err(Error::InvalidParameter { name, .. }) => assert_eq!(name, "h"),
        other => panic!("{other:?}"),
    }
    // Non-finite initial values.
    let mut integrator = make(64, 0.01, Boundary::Periodic, gauss).unwrap();
    let mut initial = vec![Complex64::new(0.1, 0.0); 64];
    initial[3] = Complex64::new(f64::NAN, 0.0);
    match integrator.run(0.0, &initial, 1, |_, _, _| {}) {
        Err(Error::InvalidParameter { name, .. }) => assert_eq!(name, "initial"),
        other => panic!("{other:?}"),
    }
}
