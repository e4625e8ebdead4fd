//! Chaos indicators from the exact tangent maps (`svi::chaos`, `Integrator::try_run_tangent`)
//! on the Hénon–Heiles system (`svi_models::HenonHeiles`, λ = 1).
//!
//! Orbits: the model's default point (x, y, ẏ) = (0, −0.2, 0), ẋ > 0 on E = 1/8, in the
//! chaotic sea (Hénon & Heiles 1964, Fig. 5); and (0, 0, 0), ẋ > 0 on E = 1/12, a regular
//! orbit (checked below: its exponent decays like ln t / t and MEGNO tends to 2).
//!
//! The independent reference of the maximal exponent is the textbook two-trajectory method
//! (Benettin et al. 1976) with `ode_solvers`' DOP853 at tolerance 10⁻¹² on Hamilton's
//! equations written out by hand: nothing of svi's methods, tangent maps or automatic
//! differentiation enters it.

use crate::allocations;
use nalgebra::{DVector, SVector, U2};
use ode_solvers::{Dop853, OutputType};
use std::ops::ControlFlow;
use std::time::Instant;
use svi::chaos::{
    Gali, GaliOptions, LyapunovSpectrum, MaximalLyapunov, MaximalOptions, Megno, MegnoOptions,
    Sali, SaliOptions, SpectrumOptions,
};
use svi::error::StepFailure;
use svi::method::registry::{METHODS, SpaceKind};
use svi::method::variational::stormer_verlet::StormerVerletWorkspace;
use svi::method::{Method, MethodInfo, StepReport};
use svi::stepping::tangent::{TangentObserver, TangentStep};
use svi::{
    Dyn, Error, Initial, Integrator, Lagrangian, Scalar, State, StormerVerlet, Structure, Svi,
    TangentMap,
};
use svi_models::HenonHeiles;

/// The chaotic orbit: the model's default point on E = 1/8.
fn chaotic() -> (HenonHeiles, Initial<U2>) {
    let model = HenonHeiles::default();
    let speed = model.initial_speed().unwrap();
    let initial = Initial::Velocity {
        q: SVector::from([0.0, model.y0]),
        v: SVector::from([speed, 0.0]),
    };
    (model, initial)
}

/// The regular orbit: (x, y, ẏ) = (0, 0, 0), ẋ = √(2E) on E = 1/12.
fn regular() -> (HenonHeiles, Initial<U2>) {
    let model = HenonHeiles {
        energy: 1.0 / 12.0,
        ..HenonHeiles::default()
    };
    let initial = Initial::Velocity {
        q: SVector::from([0.0, 0.0]),
        v: SVector::from([(2.0 * model.energy).sqrt(), 0.0]),
    };
    (model, initial)
}

/// (q, q̇) of an initial condition as one array.
fn phase(initial: &Initial<U2>) -> [f64; 4] {
    match initial {
        Initial::Velocity { q, v } => [q[0], q[1], v[0], v[1]],
        Initial::Momentum { .. } => unreachable!(),
    }
}

/// An observer that also records `read(inner)` every `every` steps.
struct Sampled<O, F> {
    inner: O,
    every: usize,
    read: F,
    samples: Vec<(f64, f64)>,
}

impl<O, F> Sampled<O, F> {
    fn new(inner: O, every: usize, read: F) -> Self {
        Sampled {
            inner,
            every,
            read,
            samples: Vec::new(),
        }
    }
}

impl<O: TangentObserver<U2>, F: FnMut(&O) -> f64> TangentObserver<U2> for Sampled<O, F> {
    fn begin(&mut self, t0: f64, state: &State<U2>) -> Result<(), Error> {
        self.inner.begin(t0, state)
    }
    fn observe(&mut self, step: &TangentStep<'_, U2>) -> Result<ControlFlow<()>, Error> {
        let flow = self.inner.observe(step)?;
        if step.step.is_multiple_of(self.every) || step.last {
            self.samples.push((step.t, (self.read)(&self.inner)));
        }
        Ok(flow)
    }
}

/// Hénon–Heiles in first-order form, two copies side by side (a reference orbit and its
/// shadow), for DOP853.
struct TwoOrbits;

impl ode_solvers::System<f64, ode_solvers::SVector<f64, 8>> for TwoOrbits {
    fn system(
        &self,
        _t: f64,
        y: &ode_solvers::SVector<f64, 8>,
        dy: &mut ode_solvers::SVector<f64, 8>,
    ) {
        for o in [0, 4] {
            let (x, v) = (y[o], y[o + 1]);
            dy[o] = y[o + 2];
            dy[o + 1] = y[o + 3];
            dy[o + 2] = -x - 2.0 * x * v;
            dy[o + 3] = -v - x * x + v * v;
        }
    }
}

/// The maximal Lyapunov exponent over [0, t_end] by two trajectories 10⁻⁸ apart (the shadow
/// displaced along (1, 1, 1, 1)/2), integrated together by DOP853 (rtol = atol = `tolerance`)
/// and renormalised to 10⁻⁸ every time unit (Benettin et al. 1976): (1/T) Σ ln(d_k/d₀), and
/// the reference orbit's (x, y, ẋ, ẏ) at t_end.
fn two_trajectory_exponent(start: [f64; 4], t_end: f64, tolerance: f64) -> (f64, [f64; 4]) {
    let (d0, interval) = (1e-8, 1.0);
    let mut y = ode_solvers::SVector::<f64, 8>::zeros();
    for i in 0..4 {
        y[i] = start[i];
        y[4 + i] = start[i] + 0.5 * d0;
    }
    let intervals = (t_end / interval).round() as usize;
    let mut log = 0.0;
    for k in 0..intervals {
        let (a, b) = (k as f64 * interval, (k + 1) as f64 * interval);
        // The controller of the work-precision peers (experiments/src/bench/peers.rs) and a
        // first trial step of 0.01 (the crate's initial-step guess is skipped).
        let mut solver = Dop853::from_param(
            TwoOrbits,
            a,
            b,
            interval,
            y,
            tolerance,
            tolerance,
            0.9,
            0.0,
            0.333,
            6.0,
            interval,
            0.01,
            1_000_000,
            1000,
            OutputType::Sparse,
        );
        solver.integrate().unwrap();
        y = *solver.y_out().last().unwrap();
        let d = (0..4)
            .map(|i| (y[4 + i] - y[i]).powi(2))
            .sum::<f64>()
            .sqrt();
        log += (d / d0).ln();
        for i in 0..4 {
            y[4 + i] = y[i] + (y[4 + i] - y[i]) * (d0 / d);
        }
    }
    (
        log / (intervals as f64 * interval),
        [y[0], y[1], y[2], y[3]],
    )
}

/// Least-squares slope of the samples with t ≥ `from`.
fn slope(samples: &[(f64, f64)], from: f64) -> f64 {
    let points: Vec<_> = samples.iter().filter(|(t, _)| *t >= from).collect();
    let n = points.len() as f64;
    let (mt, my) = points
        .iter()
        .fold((0.0, 0.0), |(a, b), (t, y)| (a + t / n, b + y / n));
    let (mut num, mut den) = (0.0, 0.0);
    for (t, y) in &points {
        num += (t - mt) * (y - my);
        den += (t - mt) * (t - mt);
    }
    num / den
}

/// The horizon of the long runs: 2·10⁵ steps of Störmer–Verlet at h = 0.05 (about 0.2 s).
const T: f64 = 1e4;
/// The step of the long runs.
const H: f64 = 0.05;

/// The Lyapunov spectrum of an orbit by Störmer–Verlet at h = [`H`] to `t_end`.
fn spectrum(
    orbit: (HenonHeiles, Initial<U2>),
    options: SpectrumOptions,
    t_end: f64,
) -> LyapunovSpectrum {
    let (model, initial) = orbit;
    let mut spectrum = LyapunovSpectrum::new(options).unwrap();
    Integrator::new(model, StormerVerlet::default())
        .try_run_tangent(0.0, initial, H, t_end, &mut spectrum)
        .unwrap();
    spectrum
}

#[test]
fn a_tangent_run_takes_the_steps_of_a_plain_run_for_every_method() {
    // The same grid, the same warm workspace: the states agree with `try_run`'s to round-off
    // for every method of ℝᴺ in the registry (explicit and implicit Euler and RK4 returned
    // the new state instead of the increment from `tangent_map` before this was tested).
    let (model, initial) = chaotic();
    for entry in METHODS.iter().filter(|e| e.space == SpaceKind::Vector) {
        let integrator = Integrator::new(model, entry.spec().vector_method().unwrap());
        let plain = integrator
            .try_run(0.0, initial, 0.05, 5.0, &Default::default(), &mut ())
            .unwrap();
        let tangent = integrator
            .try_run_tangent(0.0, initial, 0.05, 5.0, &mut ())
            .unwrap();
        let gap = (plain.state.q - tangent.state.q)
            .amax()
            .max((plain.state.y - tangent.state.y).amax());
        assert!(gap <= 1e-14, "{}: {gap:e}", entry.name);
        assert_eq!(tangent.statistics.steps, 100, "{}", entry.name);
    }
}

#[test]
fn the_spectrum_of_the_chaotic_orbit_sums_to_zero_and_pairs() {
    let clock = Instant::now();
    let every_step = spectrum(chaotic(), SpectrumOptions::default(), T);
    let elapsed = clock.elapsed();
    let l = every_step.exponents().to_vec();
    eprintln!(
        "Störmer–Verlet h = {H}, T = {T}: λ = {l:?}, Σ = {:e}, λ1 + λ4 = {:e}, λ2 + λ3 = {:e} \
         ({elapsed:?})",
        every_step.sum(),
        l[0] + l[3],
        l[1] + l[2]
    );
    assert_eq!(every_step.orthonormalizations(), 200_000);
    assert_eq!(every_step.time(), T);
    // Each step is symplectic (det Φ = 1 to round-off): the sum is round-off over T.
    assert!(every_step.sum().abs() < 1e-10, "{:e}", every_step.sum());
    assert!(l.iter().sum::<f64>().abs() < 1e-10);
    // Chaotic: λ1 near the published ≈ 0.05 (compared with DOP853 in the next test); the
    // finite-time exponents pair only up to O(1/T) (the bases at 0 and T enter as O(1)
    // logarithms over T): 10/T = 10⁻³ bounds it, and 2 ln T / T ≈ 2·10⁻³ bounds the two
    // exponents of the flow and energy directions, which decay like ln t / t.
    assert!(l[0] > 0.04 && l[0] < 0.06, "{l:?}");
    assert!((l[0] + l[3]).abs() < 10.0 / T, "{l:?}");
    assert!((l[1] + l[2]).abs() < 10.0 / T, "{l:?}");
    assert!(
        l[1].abs() < 2.0 * T.ln() / T && l[2].abs() < 2.0 * T.ln() / T,
        "{l:?}"
    );
    // Re-orthonormalising every 10 steps gives the same exponents at the re-orthonormalisation
    // times: the diagonal of R of a product is the product of the diagonals.
    let sparse = spectrum(chaotic(), SpectrumOptions::default().with_every(10), T);
    assert_eq!(sparse.orthonormalizations(), 20_000);
    for (a, b) in l.iter().zip(sparse.exponents()) {
        assert!((a - b).abs() < 1e-9, "{a} vs {b}");
    }
    // The two largest alone are the first two of the full spectrum.
    let two = spectrum(chaotic(), SpectrumOptions::default().with_count(2), T);
    assert_eq!(two.exponents().len(), 2);
    for (a, b) in l.iter().zip(two.exponents()) {
        assert!((a - b).abs() < 1e-12, "{a} vs {b}");
    }
}

#[test]
fn svi_gives_the_spectrum_of_stormer_verlet() {
    // SVI (default degree) at h = 0.1 on the same orbit: a different symplectic map, the same
    // chaotic sea. Shorter horizon (its tangent map costs a dense Hessian per step).
    let (model, initial) = chaotic();
    let t_end = 2e3;
    let clock = Instant::now();
    let mut svi = LyapunovSpectrum::new(SpectrumOptions::default()).unwrap();
    Integrator::new(model, Svi::default())
        .try_run_tangent(0.0, initial, 0.1, t_end, &mut svi)
        .unwrap();
    let elapsed = clock.elapsed();
    let verlet = spectrum(chaotic(), SpectrumOptions::default(), t_end);
    let (a, b) = (svi.exponents(), verlet.exponents());
    eprintln!(
        "SVI h = 0.1, T = {t_end}: λ = {a:?}, Σ = {:e} ({elapsed:?}); Störmer–Verlet {b:?}",
        svi.sum()
    );
    assert!(svi.sum().abs() < 1e-10, "{:e}", svi.sum());
    assert!(
        (a[0] + a[3]).abs() < 10.0 / t_end && (a[1] + a[2]).abs() < 10.0 / t_end,
        "{a:?}"
    );
    assert!(a[0] > 0.04 && a[0] < 0.08, "{a:?}");
}

#[test]
fn on_one_trajectory_the_tangent_maps_give_the_two_trajectory_exponent() {
    // SVI of high order at h = 0.05 and DOP853 at 10⁻¹³ follow the same trajectory to
    // t = 150 (checked: the end points agree to 10⁻⁷, though the chaos amplifies their
    // errors by e^{λt} ≈ e^{0.09·150} ≈ 10⁶; at t = 300 they are 3·10⁻³ apart), and the deviation starts along the same direction (1, 1, 1, 1)/2 (y = p = q̇
    // on this model): both compute ln(‖δ(t)‖/‖δ(0)‖)/t of one linearised flow, the one from
    // the exact tangent maps of the steps, the other from differences of two orbits 10⁻⁸
    // apart. What is left is the trajectories' gap and the O(d₀) nonlinearity.
    let t_end = 150.0;
    let (model, initial) = chaotic();
    let mut maximal =
        MaximalLyapunov::new(MaximalOptions::default().with_deviation(vec![0.5; 4])).unwrap();
    let run = Integrator::new(model, Svi::new(10))
        .try_run_tangent(0.0, initial, H, t_end, &mut maximal)
        .unwrap();
    let (reference, end) = two_trajectory_exponent(phase(&initial), t_end, 1e-13);
    let gap = (0..2)
        .map(|i| {
            (run.last.q[i] - end[i])
                .abs()
                .max((run.last.v[i] - end[2 + i]).abs())
        })
        .fold(0.0, f64::max);
    let lambda = maximal.exponent();
    eprintln!(
        "one trajectory to t = {t_end}: tangent maps (SVI, 10 points) {lambda}, DOP853 two \
         trajectories {reference}: {:.1e} relative, end points {gap:.1e} apart",
        lambda / reference - 1.0
    );
    // Measured: 2·10⁻⁹ apart, −5·10⁻⁸ relative (the O(d₀) = 10⁻⁸ nonlinearity of two orbits).
    assert!(gap < 1e-7, "{gap:e}");
    assert!(
        (lambda / reference - 1.0).abs() < 1e-6,
        "{lambda} vs {reference}"
    );
}

#[test]
fn the_maximal_exponent_agrees_with_two_trajectories_by_dop853() {
    // The same initial point to T = 10⁴ (2·10⁵ steps of Störmer–Verlet at h = 0.05): after
    // t ≈ 300 the two runs follow different trajectories of the chaotic sea (their errors
    // grow like e^{λt}), so this compares two finite-time samples of one ergodic average, not
    // the tangent maps (the test above does that on one trajectory). At T they agree within
    // 5 % (measured +3.7 %); the run goes on to 5T and prints the other horizons, where the
    // two samples differ by 5–13 % (the sea is sticky near its islands: finite-time
    // exponents converge slowly) — printed, not asserted.
    let (model, initial) = chaotic();
    let mut maximal = Sampled::new(
        MaximalLyapunov::new(MaximalOptions::default()).unwrap(),
        (T / H).round() as usize,
        |m: &MaximalLyapunov| m.exponent(),
    );
    let mut every_ten = MaximalLyapunov::new(MaximalOptions::default().with_every(10)).unwrap();
    let mut full = LyapunovSpectrum::new(SpectrumOptions::default()).unwrap();
    let clock = Instant::now();
    Integrator::new(model, StormerVerlet::default())
        .try_run_tangent(
            0.0,
            initial,
            H,
            5.0 * T,
            &mut (&mut maximal, &mut every_ten, &mut full),
        )
        .unwrap();
    let tangent_time = clock.elapsed();
    for &(t, lambda) in &maximal.samples {
        let clock = Instant::now();
        let (reference, _) = two_trajectory_exponent(phase(&initial), t, 1e-12);
        eprintln!(
            "maximal exponent, T = {t}: tangent maps {lambda}, DOP853 two trajectories \
             {reference} ({:?}; the tangent run to 5T {tangent_time:?}): {:+.2} %",
            clock.elapsed(),
            100.0 * (lambda / reference - 1.0)
        );
        if t == T {
            assert!(
                (lambda / reference - 1.0).abs() < 0.05,
                "T = {t}: {lambda} vs {reference}"
            );
        }
    }
    let lambda = maximal.inner.exponent();
    // Renormalising every 10 steps changes nothing but round-off (the norm of a product of
    // renormalised propagations is the product of the norms).
    assert!((every_ten.exponent() - lambda).abs() < 1e-9);
    // One vector and the first of the basis follow the same direction after a transient.
    assert!((full.exponents()[0] / lambda - 1.0).abs() < 0.01);
}

#[test]
fn the_regular_orbit_has_vanishing_exponents_and_megno_two() {
    let (model, initial) = regular();
    let mut maximal = Sampled::new(
        MaximalLyapunov::new(MaximalOptions::default()).unwrap(),
        20_000,
        |m: &MaximalLyapunov| m.exponent(),
    );
    let mut megno = Megno::new(MegnoOptions::default()).unwrap();
    let mut sali = Sampled::new(
        Sali::new(SaliOptions::default()).unwrap(),
        200,
        |s: &Sali| s.value(),
    );
    Integrator::new(model, StormerVerlet::default())
        .try_run_tangent(
            0.0,
            initial,
            H,
            T,
            &mut (&mut maximal, &mut megno, &mut sali),
        )
        .unwrap();
    // λ(t) ~ c ln t / t: the deviation grows linearly on a torus.
    let scaled: Vec<f64> = maximal
        .samples
        .iter()
        .map(|(t, l)| l * t / t.ln())
        .collect();
    eprintln!(
        "regular: λ(t) t / ln t = {scaled:?}, ⟨Y⟩ = {}, Y = {}",
        megno.mean(),
        megno.value()
    );
    assert!(scaled.iter().all(|c| *c > 0.3 && *c < 1.5), "{scaled:?}");
    assert!(maximal.inner.exponent() < 1e-3);
    // MEGNO → 2 (from below, like ln t / t).
    assert!((megno.mean() - 2.0).abs() < 0.05, "{}", megno.mean());
    // SALI stays O(1): the two vectors fall into the torus' tangent plane without aligning.
    let smallest = sali
        .samples
        .iter()
        .map(|s| s.1)
        .fold(f64::INFINITY, f64::min);
    assert!(smallest > 0.1, "{smallest}");
}

#[test]
fn megno_grows_like_half_the_exponent_on_the_chaotic_orbit() {
    let (model, initial) = chaotic();
    let mut megno = Sampled::new(
        Megno::new(MegnoOptions::default()).unwrap(),
        200,
        |m: &Megno| m.mean(),
    );
    let mut full = LyapunovSpectrum::new(SpectrumOptions::default()).unwrap();
    Integrator::new(model, StormerVerlet::default())
        .try_run_tangent(0.0, initial, H, T, &mut (&mut megno, &mut full))
        .unwrap();
    let lambda = full.exponents()[0];
    let mean = megno.inner.mean();
    let rate = slope(&megno.samples, T / 5.0);
    eprintln!(
        "chaotic: ⟨Y⟩(T) = {mean}, 2⟨Y⟩/T = {}, slope of ⟨Y⟩ on [T/5, T] = {rate}, λ1/2 = {}, \
         MEGNO's own λ = {}",
        2.0 * mean / T,
        lambda / 2.0,
        megno.inner.lyapunov()
    );
    // ⟨Y⟩ ≈ λ t / 2: its value at T (the whole history) within 5 %, its slope over the
    // last 80 % (which sees that window's finite-time λ, fluctuating by ±10 % on this orbit)
    // within 20 %.
    assert!((2.0 * mean / T / lambda - 1.0).abs() < 0.05, "{mean}");
    assert!((rate / (lambda / 2.0) - 1.0).abs() < 0.2, "{rate}");
    assert!((megno.inner.lyapunov() / lambda - 1.0).abs() < 0.01);
}

#[test]
fn sali_vanishes_exponentially_on_the_chaotic_orbit_and_bounds_gali_2() {
    // SALI/√2 ≤ GALI₂ ≤ SALI at every step, on both orbits, from the same two vectors.
    struct Both {
        sali: Sali,
        gali: Gali,
        worst: f64,
        seen: usize,
    }
    impl TangentObserver<U2> for Both {
        fn begin(&mut self, t0: f64, state: &State<U2>) -> Result<(), Error> {
            self.sali.begin(t0, state)?;
            self.gali.begin(t0, state)
        }
        fn observe(&mut self, step: &TangentStep<'_, U2>) -> Result<ControlFlow<()>, Error> {
            let flow = self.sali.observe(step)?;
            let _ = self.gali.observe(step)?;
            let (s, g) = (self.sali.value(), self.gali.value());
            // Both from unit vectors: absolute round-off of a few ε.
            let excess = (g - s).max(s / std::f64::consts::SQRT_2 - g);
            self.worst = self.worst.max(excess);
            self.seen += 1;
            Ok(flow)
        }
    }
    for (name, orbit, t_end) in [("chaotic", chaotic(), 1e3), ("regular", regular(), 1e3)] {
        let (model, initial) = orbit;
        let mut both = Both {
            sali: Sali::new(SaliOptions::default().with_stop_below(1e-12)).unwrap(),
            gali: Gali::new(GaliOptions::default()).unwrap(),
            worst: f64::NEG_INFINITY,
            seen: 0,
        };
        let run = Integrator::new(model, StormerVerlet::default())
            .try_run_tangent(0.0, initial, H, t_end, &mut both)
            .unwrap();
        eprintln!(
            "{name}: SALI {:e} GALI₂ {:e} at t = {} (stopped: {}), bound excess {:e} over {} steps",
            both.sali.value(),
            both.gali.value(),
            both.sali.time(),
            run.stopped,
            both.worst,
            both.seen
        );
        assert!(both.worst <= 1e-15, "{name}: {:e}", both.worst);
        assert!(both.seen > 1000);
        match name {
            "chaotic" => {
                // Below 10⁻¹² (the stop) well before t = 1000: e^{−(λ1 − λ2) t} with
                // λ1 − λ2 ≈ 0.05 reaches it near t ≈ 550.
                assert!(
                    run.stopped && both.sali.time() < 800.0,
                    "{}",
                    both.sali.time()
                );
                assert!(both.sali.value() < 1e-12);
            }
            _ => {
                assert!(!run.stopped);
                assert!(both.sali.value() > 0.1 && both.gali.value() > 0.05);
            }
        }
    }
}

#[test]
fn gali_of_higher_order_follows_the_dimension_of_the_torus() {
    // Regular orbit on a 2-torus (N = 2): GALI₂ stays O(1), GALI₃ ∝ t⁻², GALI₄ ∝ t⁻⁴
    // (Skokos et al. 2007, eq. 21); chaotic: every GALI_k falls exponentially.
    let (model, initial) = regular();
    let gali = |k| Gali::new(GaliOptions::default().with_k(k)).unwrap();
    let mut g3 = Sampled::new(gali(3), 20_000, |g: &Gali| g.value());
    let mut g4 = Sampled::new(gali(4), 20_000, |g: &Gali| g.value());
    Integrator::new(model, StormerVerlet::default())
        .try_run_tangent(0.0, initial, H, T, &mut (&mut g3, &mut g4))
        .unwrap();
    let power = |samples: &[(f64, f64)]| {
        let logs: Vec<_> = samples.iter().map(|(t, g)| (t.ln(), g.ln())).collect();
        slope(&logs, 1e3f64.ln())
    };
    let (p3, p4) = (power(&g3.samples), power(&g4.samples));
    eprintln!("regular: GALI₃ ∝ t^{p3:.2}, GALI₄ ∝ t^{p4:.2} on [10³, 10⁴]");
    // The power laws hold for t → ∞; fitted on [10³, 10⁴] the exponents come out about 20 %
    // steeper (measured −2.37 and −4.55), with p₄ ≈ 2 p₃ as the theory has it.
    assert!((p3 + 2.0).abs() < 0.5, "{p3}");
    assert!((p4 + 4.0).abs() < 0.8, "{p4}");
    assert!((p4 / p3 - 2.0).abs() < 0.2, "{p3} {p4}");
}

#[test]
fn bad_options_and_a_method_without_tangent_map_are_typed_errors() {
    let name = |error: Error| match error {
        Error::InvalidParameter { name, .. } => name,
        other => panic!("expected an invalid parameter, got {other:?}"),
    };
    assert_eq!(
        name(LyapunovSpectrum::new(SpectrumOptions::default().with_every(0)).unwrap_err()),
        "every"
    );
    assert_eq!(
        name(LyapunovSpectrum::new(SpectrumOptions::default().with_count(0)).unwrap_err()),
        "count"
    );
    assert_eq!(
        name(MaximalLyapunov::new(MaximalOptions::default().with_every(0)).unwrap_err()),
        "every"
    );
    assert_eq!(
        name(Gali::new(GaliOptions::default().with_k(0)).unwrap_err()),
        "k"
    );
    for threshold in [f64::NAN, f64::INFINITY, 0.0, -1.0] {
        assert_eq!(
            name(Sali::new(SaliOptions::default().with_stop_below(threshold)).unwrap_err()),
            "stop_below"
        );
        assert_eq!(
            name(Gali::new(GaliOptions::default().with_stop_below(threshold)).unwrap_err()),
            "stop_below"
        );
    }
    // Options that need the dimension 2N = 4 are refused when the run begins, before a step.
    let (model, initial) = chaotic();
    let integrator = Integrator::new(model, StormerVerlet::default());
    let rejected = |observer: &mut dyn TangentObserver<U2>| {
        let failure = integrator
            .try_run_tangent(0.0, initial, H, 1.0, observer)
            .unwrap_err();
        assert!(failure.partial.is_none());
        name(failure.error)
    };
    assert_eq!(
        rejected(&mut LyapunovSpectrum::new(SpectrumOptions::default().with_count(5)).unwrap()),
        "count"
    );
    assert_eq!(
        rejected(&mut Gali::new(GaliOptions::default().with_k(5)).unwrap()),
        "k"
    );
    let wrong_length = MaximalOptions::default().with_deviation(vec![1.0, 0.0, 0.0]);
    assert_eq!(
        rejected(&mut MaximalLyapunov::new(wrong_length).unwrap()),
        "deviation"
    );
    let not_finite = MegnoOptions::default().with_deviation(vec![1.0, f64::NAN, 0.0, 0.0]);
    assert_eq!(rejected(&mut Megno::new(not_finite).unwrap()), "deviation");
    let zero = SaliOptions::default().with_deviations([vec![0.0; 4], vec![1.0, 0.0, 0.0, 0.0]]);
    assert_eq!(rejected(&mut Sali::new(zero).unwrap()), "deviations");
    let parallel = GaliOptions::default()
        .with_deviations(vec![vec![1.0, 2.0, 0.0, 0.0], vec![-2.0, -4.0, 0.0, 0.0]]);
    assert_eq!(rejected(&mut Gali::new(parallel).unwrap()), "deviations");
    // A re-orthonormalisation interval so long that the vectors overflow: 4·10⁵ steps of
    // h = 0.05 grow them like e^{λ1 t} ≈ e^{0.05 · 2·10⁴} = e^{1000} > 10³⁰⁸. A typed error at
    // the step of the re-orthonormalisation, with the run up to there.
    let mut careless =
        LyapunovSpectrum::new(SpectrumOptions::default().with_every(400_000)).unwrap();
    let failure = integrator
        .try_run_tangent(0.0, initial, H, 3e4, &mut careless)
        .unwrap_err();
    eprintln!("{}", failure.error);
    assert!(
        matches!(failure.error, Error::NonFinite { step: 399_999, .. }),
        "{:?}",
        failure.error
    );
    assert_eq!(failure.partial.unwrap().statistics.steps, 400_000);
    // A method whose tangent map is not available is named.
    let failure = Integrator::new(model, WithoutTangent::default())
        .try_run_tangent(0.0, initial, H, 1.0, &mut ())
        .unwrap_err();
    match &failure.error {
        Error::InvalidParameter { name, reason } => {
            assert_eq!(name, "method");
            assert!(
                reason.contains("verlet-without-tangent") && reason.contains("step 0"),
                "{reason}"
            );
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(failure.partial.unwrap().statistics.steps, 0);
    // A step that fails carries its index and time.
    let failure = integrator
        .try_run_tangent(
            0.0,
            Initial::Velocity {
                q: SVector::from([0.0, 0.0]),
                v: SVector::from([3.0, 3.0]),
            },
            0.5,
            100.0,
            &mut (),
        )
        .unwrap_err();
    eprintln!("{}", failure.error);
    assert!(failure.error.step().is_some() && failure.error.time().is_some());
}

#[test]
fn an_observer_stops_the_run_and_points_are_completed_on_request() {
    struct StopAt {
        step: usize,
        points: usize,
        energy: f64,
    }
    impl TangentObserver<U2> for StopAt {
        fn wants_point(&self, step: usize) -> bool {
            step.is_multiple_of(2)
        }
        fn observe(&mut self, step: &TangentStep<'_, U2>) -> Result<ControlFlow<()>, Error> {
            assert_eq!(step.point.is_some(), step.step.is_multiple_of(2));
            if let Some(point) = step.point {
                assert_eq!(point.t, step.t);
                assert_eq!(point.q, step.state.q);
                self.energy = HenonHeiles::default().energy_of(&point.q, &point.v);
                self.points += 1;
            }
            Ok(if step.step == self.step {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            })
        }
    }
    let (model, initial) = chaotic();
    let mut stop = StopAt {
        step: 7,
        points: 0,
        energy: 0.0,
    };
    let run = Integrator::new(model, StormerVerlet::default())
        .try_run_tangent(0.0, initial, H, 10.0, &mut stop)
        .unwrap();
    assert!(run.stopped);
    assert_eq!(run.statistics.steps, 7);
    assert_eq!(stop.points, 3);
    assert!((stop.energy - 0.125).abs() < 1e-3, "{}", stop.energy);
}

/// Hénon–Heiles as a run-time-size model (`Lagrangian<Dyn>`, n = 2).
struct HenonHeilesDyn;

impl Lagrangian<Dyn> for HenonHeilesDyn {
    const TIME_DEPENDENT: bool = false;
    const STRUCTURE: Structure = Structure::ConstantMass;
    fn dimension(&self) -> usize {
        2
    }
    fn lagrangian<D: Scalar>(&self, _t: D, q: &DVector<D>, v: &DVector<D>) -> D {
        let (x, y) = (q[0], q[1]);
        (v[0] * v[0] + v[1] * v[1]) * 0.5 - (x * x + y * y) * 0.5 - (x * x * y - y * y * y / 3.0)
    }
}

#[test]
fn the_indicators_run_on_a_runtime_size_model() {
    // The same orbit written as a Lagrangian<Dyn>: the same numbers to round-off (amplified
    // by the chaos over T = 200: e^{0.07·200} ≈ 10⁶ from 10⁻¹⁶).
    let t_end = 200.0;
    let (model, initial) = chaotic();
    let [x, y, vx, vy] = phase(&initial);
    let mut fixed = (
        LyapunovSpectrum::new(SpectrumOptions::default()).unwrap(),
        Megno::new(MegnoOptions::default()).unwrap(),
        Gali::new(GaliOptions::default().with_k(3)).unwrap(),
    );
    Integrator::new(model, StormerVerlet::default())
        .try_run_tangent(0.0, initial, H, t_end, &mut fixed)
        .unwrap();
    let mut runtime = (
        LyapunovSpectrum::new(SpectrumOptions::default()).unwrap(),
        Megno::new(MegnoOptions::default()).unwrap(),
        Gali::new(GaliOptions::default().with_k(3)).unwrap(),
    );
    let initial = Initial::Velocity {
        q: DVector::from_vec(vec![x, y]),
        v: DVector::from_vec(vec![vx, vy]),
    };
    Integrator::new(HenonHeilesDyn, StormerVerlet::default())
        .try_run_tangent(0.0, initial, H, t_end, &mut runtime)
        .unwrap();
    for (a, b) in fixed.0.exponents().iter().zip(runtime.0.exponents()) {
        assert!((a - b).abs() < 1e-8, "{a} vs {b}");
    }
    assert!((fixed.1.mean() - runtime.1.mean()).abs() < 1e-8 * fixed.1.mean());
    assert!((fixed.2.value() / runtime.2.value() - 1.0).abs() < 1e-6);
}

/// Allocations made by a tangent run of `steps` steps with `observer`.
fn allocations_of(observer: &mut dyn TangentObserver<U2>, steps: usize) -> usize {
    let (model, initial) = chaotic();
    let integrator = Integrator::new(model, StormerVerlet::default());
    let before = allocations::count();
    integrator
        .try_run_tangent(0.0, initial, H, H * steps as f64, observer)
        .unwrap();
    allocations::count() - before
}

#[test]
fn observing_a_step_allocates_nothing() {
    let observers = || {
        (
            LyapunovSpectrum::new(SpectrumOptions::default()).unwrap(),
            MaximalLyapunov::new(MaximalOptions::default()).unwrap(),
            Megno::new(MegnoOptions::default()).unwrap(),
            (
                Sali::new(SaliOptions::default()).unwrap(),
                Gali::new(GaliOptions::default().with_k(4)).unwrap(),
            ),
        )
    };
    let cost = |steps| allocations_of(&mut observers(), steps) - allocations_of(&mut (), steps);
    assert_eq!(cost(20), cost(2000));
    // Nor does the loop itself, with Störmer–Verlet on a fixed-size model.
    assert_eq!(allocations_of(&mut (), 20), allocations_of(&mut (), 2000));
}

/// Time per step of a plain run, a tangent run and the indicators (run with `--ignored
/// --nocapture`; timings are not asserted).
#[test]
#[ignore = "a measurement: cargo test --release --test integration chaos::cost -- --ignored --nocapture"]
fn cost_per_step() {
    fn time<F: FnMut()>(steps: usize, mut run: F) -> f64 {
        run();
        let clock = Instant::now();
        let repeats = 3;
        for _ in 0..repeats {
            run();
        }
        clock.elapsed().as_secs_f64() / (repeats * steps) as f64 * 1e9
    }
    let (model, initial) = chaotic();
    let steps = 100_000;
    let t_end = H * steps as f64;
    macro_rules! measure {
        ($label:expr, $method:expr, $steps:expr) => {{
            let integrator = Integrator::new(model, $method);
            let steps = $steps;
            let t_end = H * steps as f64;
            let plain = time(steps, || { integrator.try_run(0.0, initial, H, t_end, &Default::default(), &mut ()).unwrap(); });
            let bare = time(steps, || { integrator.try_run_tangent(0.0, initial, H, t_end, &mut ()).unwrap(); });
            let mut spectrum = LyapunovSpectrum::new(SpectrumOptions::default()).unwrap();
            let full = time(steps, || { integrator.try_run_tangent(0.0, initial, H, t_end, &mut spectrum).unwrap(); });
            let mut spectrum10 = LyapunovSpectrum::new(SpectrumOptions::default().with_every(10)).unwrap();
            let full10 = time(steps, || { integrator.try_run_tangent(0.0, initial, H, t_end, &mut spectrum10).unwrap(); });
            let mut maximal = MaximalLyapunov::new(MaximalOptions::default()).unwrap();
            let one = time(steps, || { integrator.try_run_tangent(0.0, initial, H, t_end, &mut maximal).unwrap(); });
            let mut megno = Megno::new(MegnoOptions::default()).unwrap();
            let meg = time(steps, || { integrator.try_run_tangent(0.0, initial, H, t_end, &mut megno).unwrap(); });
            let mut sali = Sali::new(SaliOptions::default()).unwrap();
            let sal = time(steps, || { integrator.try_run_tangent(0.0, initial, H, t_end, &mut sali).unwrap(); });
            let mut gali = Gali::new(GaliOptions::default().with_k(4)).unwrap();
            let gal = time(steps, || { integrator.try_run_tangent(0.0, initial, H, t_end, &mut gali).unwrap(); });
            eprintln!(
                "{:<16} ns/step: plain {plain:.0} | tangent run {bare:.0} | spectrum {full:.0} (every 10: {full10:.0}) | maximal {one:.0} | MEGNO {meg:.0} | SALI {sal:.0} | GALI_4 {gal:.0}",
                $label
            );
        }};
    }
    let _ = t_end;
    measure!("verlet", StormerVerlet::default(), steps);
    measure!("svi (default)", Svi::default(), steps / 10);
}
/// Störmer–Verlet whose tangent map is not available.
#[derive(Debug, Clone, Default)]
struct WithoutTangent(StormerVerlet);

impl Method<U2> for WithoutTangent {
    type Workspace = StormerVerletWorkspace<U2>;
    fn info(&self) -> MethodInfo {
        MethodInfo {
            name: "verlet-without-tangent",
            ..Method::<U2>::info(&self.0)
        }
    }
    fn workspace<L: Lagrangian<U2>>(&self, model: &L, h: f64) -> Result<Self::Workspace, Error> {
        self.0.workspace(model, h)
    }
    fn step<L: Lagrangian<U2>>(
        &self,
        model: &L,
        workspace: &mut Self::Workspace,
        t: f64,
        h: f64,
        state: &State<U2>,
        increment: &mut State<U2>,
    ) -> Result<StepReport, StepFailure> {
        self.0.step(model, workspace, t, h, state, increment)
    }
    fn tangent_map<L: Lagrangian<U2>>(
        &self,
        _: &L,
        _: &mut Self::Workspace,
        _: f64,
        _: f64,
        _: &State<U2>,
    ) -> Result<(State<U2>, TangentMap<U2>, StepReport), StepFailure> {
        Err(StepFailure::Unsupported {
            option: "tangent map",
            reason: "not implemented",
        })
    }
}
