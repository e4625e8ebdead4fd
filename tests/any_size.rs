//! Every method of ℝᴺ on models of any size: the same Kepler problem as the compiled zoo model
//! (`Lagrangian<U2>`), written by hand as a run-time-size model (`Lagrangian<Dyn>`) and written
//! as text (a `TextLagrangian<Dyn>`), and the orders of the registry observed on a run-time-size
//! model.
//!
//! References: the zoo's `Kepler` (its trajectory is the reference of the other two: the
//! dimension changes how derivatives are taken — vector duals or scalar sweeps —, never the
//! numbers beyond round-off), and the closed form q(t) = cos t of the oscillator q̈ = −q.

use nalgebra::allocator::Allocator;
use nalgebra::{DVector, DefaultAllocator, SVector, U2};
use svi::method::registry::{Entry, METHODS, SpaceKind, VectorMethodVisitor};
use svi::model::local::{LocalDefaults, LocalLagrangian, Terms};
use svi::model::text::{TextLagrangian, TextModel, TextSpec};
use svi::verify::observed_order;
use svi::{
    Defaults, Dimension, Dyn, Integrator, Lagrangian, Method, MethodSpec, Scalar, Structure,
};
use svi_models::{Fput, Kepler, RelativisticChain};

/// Kepler written as a run-time-size model: L = |q̇|²/2 + 1/|q| on ℝⁿ with n = 2 chosen when
/// the model is built.
struct KeplerDyn {
    n: usize,
}

impl Lagrangian<Dyn> for KeplerDyn {
    const TIME_DEPENDENT: bool = false;
    const STRUCTURE: Structure = Structure::ConstantMass;

    fn dimension(&self) -> usize {
        self.n
    }

    fn lagrangian<D: Scalar>(&self, _t: D, q: &DVector<D>, v: &DVector<D>) -> D {
        v.dot(v) * 0.5 + q.dot(q).sqrt().recip()
    }
}

/// A text model of the given Lagrangian and coordinates, as the command line builds it.
fn text(lagrangian: &str, coordinates: &[&str]) -> TextLagrangian<Dyn, false, false, true> {
    let spec = TextSpec {
        lagrangian: lagrangian.into(),
        coordinates: coordinates.iter().map(|name| (*name).into()).collect(),
        ..TextSpec::default()
    };
    TextLagrangian::new(TextModel::new(&spec).unwrap()).unwrap()
}

/// Runs a method over `steps` steps of size `h` and returns (q, q̇) at the end (or the error).
struct Run<L> {
    model: L,
    q: Vec<f64>,
    v: Vec<f64>,
    h: f64,
    steps: usize,
}

impl<L: Lagrangian<N>, N: Dimension> VectorMethodVisitor<N> for Run<L>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    type Output = Result<Vec<f64>, String>;

    fn visit<M: Method<N> + Clone>(self, method: M) -> Self::Output {
        let n = N::from_usize(self.q.len());
        let vector =
            |x: &[f64]| nalgebra::OVector::<f64, N>::from_column_slice_generic(n, nalgebra::U1, x);
        let integrator = Integrator::new(self.model, method);
        let run = integrator
            .run_from_velocity(
                0.0,
                vector(&self.q),
                vector(&self.v),
                self.h,
                self.h * self.steps as f64,
                &mut (),
            )
            .map_err(|failure| failure.to_string())?;
        Ok(run
            .last
            .q
            .iter()
            .chain(run.last.v.iter())
            .copied()
            .collect())
    }
}

/// `visitor` with `spec`'s method as an [`svi::method::any::AnyMethod`], as the command line
/// runs it: the stepping loop is compiled once per model, not per model and method (that
/// both take the same steps is `svi`'s registry test).
fn visit<V: VectorMethodVisitor<N>, N: Dimension>(
    spec: &MethodSpec,
    visitor: V,
) -> Result<V::Output, svi::Error>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    Ok(visitor.visit(spec.vector_method()?))
}

fn vector_methods() -> impl Iterator<Item = &'static Entry> {
    METHODS
        .iter()
        .filter(|entry| entry.space == SpaceKind::Vector)
}

#[test]
fn every_method_runs_kepler_alike_compiled_at_run_time_size_and_as_text() {
    let (_, q0, v0) = Kepler::default().initial_state();
    let (q, v) = (q0.as_slice().to_vec(), v0.as_slice().to_vec());
    let run = |entry: &'static Entry, which: usize| {
        let (q, v, h, steps) = (q.clone(), v.clone(), 0.01, 100);
        let spec = entry.spec();
        match which {
            0 => visit::<_, U2>(
                &spec,
                Run {
                    model: Kepler::default(),
                    q,
                    v,
                    h,
                    steps,
                },
            ),
            1 => visit::<_, Dyn>(
                &spec,
                Run {
                    model: KeplerDyn { n: 2 },
                    q,
                    v,
                    h,
                    steps,
                },
            ),
            _ => visit::<_, Dyn>(
                &spec,
                Run {
                    model: text("0.5*(vx^2 + vy^2) + 1/sqrt(x^2 + y^2)", &["x", "y"]),
                    q,
                    v,
                    h,
                    steps,
                },
            ),
        }
        .unwrap()
    };
    for entry in vector_methods() {
        let compiled = run(entry, 0);
        for which in [1, 2] {
            match (&compiled, run(entry, which)) {
                (Ok(a), Ok(b)) => {
                    let gap = a
                        .iter()
                        .zip(&b)
                        .map(|(x, y)| (x - y).abs())
                        .fold(0.0, f64::max);
                    assert!(
                        gap <= 1e-12,
                        "{} ({which}): {gap:e}\n{a:?}\n{b:?}",
                        entry.name
                    );
                }
                // The multiscale method needs a fast frequency Kepler does not have: it must
                // refuse alike.
                (Err(a), Err(b)) if entry.name == "multiscale" => assert_eq!(a, &b),
                (a, b) => panic!("{} ({which}): {a:?} vs {b:?}", entry.name),
            }
        }
    }
}

#[test]
fn every_method_reaches_its_registry_order_on_a_run_time_size_text_model() {
    // q̈ = −q from q = 1, q̇ = 0 over [0, 2]: q(2) = cos 2. The multiscale method integrates
    // the oscillation it is built on exactly; the others converge at their registry order.
    let model = || text("0.5*vq^2 - 0.5*q^2", &["q"]);
    for entry in vector_methods().filter(|entry| entry.name != "multiscale") {
        let spec = entry.spec();
        let order = spec.info().unwrap().order;
        let error = |h: f64| {
            let end = visit::<_, Dyn>(
                &spec,
                Run {
                    model: model(),
                    q: vec![1.0],
                    v: vec![0.0],
                    h,
                    steps: (2.0 / h).round() as usize,
                },
            )
            .unwrap()
            .unwrap();
            (end[0] - 2f64.cos()).abs()
        };
        // Halve the step from one step over [0, 2] until the error is below 1e-5 (1e-3 for
        // orders 1 and 2: in the asymptotic range), then fit over it and two more halvings
        // above round-off.
        let target = if order <= 2 { 1e-3 } else { 1e-5 };
        let mut first = 2.0;
        while error(first) > target {
            first /= 2.0;
        }
        let steps = [first, first / 2.0, first / 4.0];
        let errors: Vec<f64> = steps.iter().map(|&h| error(h)).collect();
        let observed = observed_order(&steps, &errors, 1e-12)
            .unwrap_or_else(|e| panic!("{}: {e}, errors {errors:?}", entry.name));
        assert!(
            (observed - order as f64).abs() < 0.4,
            "{}: observed {observed:.2}, registry {order}, errors {errors:?}",
            entry.name
        );
    }
}

/// The Kepler zoo model and its run-time-size twin agree on the derived quantities the
/// observers print (energy, angular momentum).
#[test]
fn run_time_size_kepler_has_the_zoo_energy() {
    use svi::LagrangianExt;
    let (q, v) = (SVector::from([0.5, 0.1]), SVector::from([0.2, 1.3]));
    let (qd, vd) = (
        DVector::from_column_slice(q.as_slice()),
        DVector::from_column_slice(v.as_slice()),
    );
    let (fixed, run_time) = (
        Kepler::default().energy(0.0, &q, &v),
        KeplerDyn { n: 2 }.energy(0.0, &qd, &vd),
    );
    assert!((fixed - run_time).abs() <= 1e-15, "{fixed} vs {run_time}");
}

/// A dense method on a run-time-size model too large for dense matrices is refused before
/// anything is allocated, with an error that names the method and the size and says what
/// serves; the same model of moderate size runs.
#[test]
fn a_dense_method_refuses_a_model_too_large_for_it() {
    for (entry, n) in [("svi", 100_000), ("midpoint", 100_000), ("verlet", 20_000)] {
        let spec = svi::method::registry::find(entry).unwrap().spec();
        let mut q = vec![0.0; n];
        q[0] = 1.0;
        let error = visit::<_, Dyn>(
            &spec,
            Run {
                model: KeplerDyn { n },
                q,
                v: vec![0.0; n],
                h: 0.1,
                steps: 1,
            },
        )
        .unwrap()
        .unwrap_err();
        assert!(
            error.contains(entry)
                && error.contains(&format!("{n} coordinates"))
                && error.contains("local terms"),
            "{error}"
        );
    }
}

/// The outer Solar System (HLW §I.2.4, Fig. I.2.4) over 200 000 days with h = 10 days:
/// explicit Euler's planets spiral out, symplectic Euler and Störmer–Verlet keep them on
/// their orbits with a bounded energy error, and SVI at h = 200 days keeps the energy to
/// round-off. The zoo's `nbody` is written by hand; the same 18-coordinate Lagrangian
/// written as text ends at the same place.
mod outer_solar_system {
    use super::*;
    use svi::LagrangianExt;
    use svi::observer::EnergyError;
    use svi_models::NBody;

    /// Final state and the largest relative energy error of `method` with step `h`.
    fn run(method: &str, h: f64, t_end: f64) -> (Vec<f64>, f64) {
        struct Orbit {
            h: f64,
            t_end: f64,
        }
        impl VectorMethodVisitor<Dyn> for Orbit {
            type Output = (Vec<f64>, f64);
            fn visit<M: Method<Dyn> + Clone>(self, method: M) -> Self::Output {
                let model = NBody::default();
                let (t0, q0, v0) = model.initial_state();
                let energy = model.energy(t0, &q0, &v0);
                let mut error = EnergyError::default();
                let run = Integrator::new(model, method)
                    .run_from_velocity(t0, q0, v0, self.h, self.t_end, &mut error)
                    .unwrap();
                let state = run
                    .last
                    .q
                    .iter()
                    .chain(run.last.v.iter())
                    .copied()
                    .collect();
                (state, error.max / energy.abs())
            }
        }
        let spec = svi::method::registry::find(method).unwrap().spec();
        visit::<_, Dyn>(&spec, Orbit { h, t_end }).unwrap()
    }

    /// Jupiter's distance from the Sun.
    fn jupiter(state: &[f64]) -> f64 {
        (0..3)
            .map(|k| (state[3 + k] - state[k]).powi(2))
            .sum::<f64>()
            .sqrt()
    }

    #[test]
    fn explicit_euler_spirals_out_and_the_symplectic_methods_stay() {
        let (start, _) = run("explicit-euler", 10.0, 10.0);
        let r0 = jupiter(&start);
        let (euler, euler_energy) = run("explicit-euler", 10.0, 200_000.0);
        assert!(jupiter(&euler) > 1.5 * r0, "{} vs {r0}", jupiter(&euler));
        assert!(euler_energy > 0.1, "{euler_energy:e}");
        // Symplectic Euler over a tenth of the span: its implicit steps take second derivatives
        // of the 18-coordinate Lagrangian by scalar sweeps (the whole span takes seconds).
        for (method, t_end) in [("symplectic-euler", 20_000.0), ("verlet", 200_000.0)] {
            let (end, energy) = run(method, 10.0, t_end);
            let r = jupiter(&end);
            assert!((4.9..5.5).contains(&r), "{method}: Jupiter at {r}");
            assert!(energy < 5e-3, "{method}: {energy:e}");
        }
        let (_, energy) = run("svi", 200.0, 200_000.0);
        assert!(energy < 1e-12, "svi: {energy:e}");
    }

    /// The outer Solar System written as text from the zoo model's bodies: ½ mᵢ |q̇ᵢ|² for
    /// each body and G mᵢ mⱼ / |qᵢ − qⱼ| for each pair, in the coordinates `<body>_x`, … of
    /// the zoo model.
    fn as_text(model: &NBody) -> TextLagrangian<Dyn, false, false, true> {
        let bodies = model.bodies();
        let axes = ["x", "y", "z"];
        let coordinate = |body: &svi_models::Body, axis: &str| format!("{}_{axis}", body.name);
        let mut terms: Vec<String> = bodies
            .iter()
            .map(|body| {
                let speed: Vec<String> = axes
                    .iter()
                    .map(|axis| format!("v{}^2", coordinate(body, axis)))
                    .collect();
                format!("0.5*{:?}*({})", body.mass, speed.join(" + "))
            })
            .collect();
        for (i, a) in bodies.iter().enumerate() {
            for b in &bodies[i + 1..] {
                let distance: Vec<String> = axes
                    .iter()
                    .map(|axis| format!("({} - {})^2", coordinate(a, axis), coordinate(b, axis)))
                    .collect();
                terms.push(format!(
                    "{:?}*{:?}*{:?}/sqrt({})",
                    model.g,
                    a.mass,
                    b.mass,
                    distance.join(" + ")
                ));
            }
        }
        let names = model.coordinate_names();
        let names: Vec<&str> = names.iter().map(String::as_str).collect();
        text(&terms.join(" + "), &names)
    }

    /// The text version ends where the zoo model does, to 1e-10 AU in every position: 1000
    /// steps of Störmer–Verlet with h = 10 days, 20 steps of SVI with h = 200 days.
    #[test]
    fn the_outer_solar_system_written_as_text_matches_the_zoo_model() {
        let model = NBody::default();
        let (_, q0, v0) = model.initial_state();
        let (q, v) = (q0.as_slice().to_vec(), v0.as_slice().to_vec());
        for (method, h, steps) in [("verlet", 10.0, 1000), ("svi", 200.0, 20)] {
            let spec = svi::method::registry::find(method).unwrap().spec();
            let run = |which: usize| {
                let (q, v) = (q.clone(), v.clone());
                match which {
                    0 => visit::<_, Dyn>(
                        &spec,
                        Run {
                            model: NBody::default(),
                            q,
                            v,
                            h,
                            steps,
                        },
                    ),
                    _ => visit::<_, Dyn>(
                        &spec,
                        Run {
                            model: as_text(&model),
                            q,
                            v,
                            h,
                            steps,
                        },
                    ),
                }
                .unwrap()
                .unwrap()
            };
            let (zoo, text) = (run(0), run(1));
            let gap = zoo[..18]
                .iter()
                .zip(&text[..18])
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            assert!(gap <= 1e-10, "{method}: {gap:e}");
            // Jupiter moved along its orbit (10 000 and 4000 days of its 4333-day period).
            let moved = (zoo[3] - q[3]).hypot(zoo[4] - q[4]);
            assert!(moved > 1.0, "{method}: Jupiter moved {moved}");
        }
    }
}

/// A Lagrangian of local terms differentiated as one function of all coordinates: the
/// derivatives its terms assemble ([`Lagrangian::terms`]) taken away, an independent
/// computation of the same L.
struct Whole<L>(Terms<L>);

impl<L: LocalLagrangian> Lagrangian<Dyn> for Whole<L> {
    const TIME_DEPENDENT: bool = L::TIME_DEPENDENT;
    const STRUCTURE: Structure = L::STRUCTURE;

    fn dimension(&self) -> usize {
        self.0.0.dimension()
    }

    fn lagrangian<D: Scalar>(&self, t: D, q: &DVector<D>, v: &DVector<D>) -> D {
        self.0.lagrangian(t, q, v)
    }
}

/// Runs every method of ℝᴺ on `model` (its derivatives assembled term by term) and on
/// `Whole(model)` (automatic differentiation of all of L) and checks that they agree.
fn assert_terms_run_as_the_whole<L: LocalLagrangian + LocalDefaults + Clone>(model: L) {
    let (_, q0, v0) = model.initial_state();
    let (q, v) = (q0.as_slice().to_vec(), v0.as_slice().to_vec());
    let (h, steps) = (model.default_step(), 40);
    for entry in vector_methods() {
        let spec = entry.spec();
        let terms = visit::<_, Dyn>(
            &spec,
            Run {
                model: Terms(model.clone()),
                q: q.clone(),
                v: v.clone(),
                h,
                steps,
            },
        )
        .unwrap();
        let whole = visit::<_, Dyn>(
            &spec,
            Run {
                model: Whole(Terms(model.clone())),
                q: q.clone(),
                v: v.clone(),
                h,
                steps,
            },
        )
        .unwrap();
        match (terms, whole) {
            (Ok(a), Ok(b)) => {
                let gap = a
                    .iter()
                    .zip(&b)
                    .map(|(x, y)| (x - y).abs())
                    .fold(0.0, f64::max);
                assert!(gap <= 1e-12, "{} on {}: {gap:e}", entry.name, model.name());
            }
            // The multiscale method needs a fast frequency the chains do not declare.
            (Err(a), Err(b)) if entry.name == "multiscale" => assert_eq!(a, b),
            (a, b) => panic!("{} on {}: {a:?} vs {b:?}", entry.name, model.name()),
        }
    }
}

/// Every method of ℝᴺ runs a sum of local terms — constant mass (FPUT) and a mass matrix that
/// depends on q̇ (the relativistic chain) — as the same Lagrangian differentiated whole.
#[test]
fn every_method_runs_a_sum_of_local_terms_as_the_lagrangian_differentiated_whole() {
    let mut fput = Fput::default();
    fput.set_parameter("n", 6.0).unwrap();
    fput.set_parameter("beta", 0.5).unwrap();
    assert_terms_run_as_the_whole(fput);
    // At 0.8 c (the default) momenta exceed m c: the inverse Legendre map started at p
    // must halve its steps to stay inside the light cone.
    let mut chain = RelativisticChain::default();
    chain.set_parameter("n", 6.0).unwrap();
    assert_terms_run_as_the_whole(chain);
}

/// The Hessian blocks a sum of local terms assembles are those of the whole L.
#[test]
fn local_terms_assemble_the_hessian_blocks_of_the_whole_lagrangian() {
    use svi::LagrangianExt;
    let mut chain = RelativisticChain::default();
    chain.set_parameter("n", 7.0).unwrap();
    let q = DVector::from_fn(7, |i, _| 0.3 * (i as f64 + 1.0).sin());
    let v = DVector::from_fn(7, |i, _| 0.2 * (i as f64 * 0.7).cos());
    let terms = Terms(chain.clone()).second_derivatives(0.0, &q, &v);
    let whole = Whole(Terms(chain)).second_derivatives(0.0, &q, &v);
    assert!((terms.value - whole.value).abs() <= 1e-14);
    for (name, a, b) in [
        ("q", terms.q.as_slice(), whole.q.as_slice()),
        ("v", terms.v.as_slice(), whole.v.as_slice()),
        ("qq", terms.qq.as_slice(), whole.qq.as_slice()),
        ("qv", terms.qv.as_slice(), whole.qv.as_slice()),
        ("vv", terms.vv.as_slice(), whole.vv.as_slice()),
    ] {
        let gap = a
            .iter()
            .zip(b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
        assert!(gap <= 1e-13, "{name}: {gap:e}");
    }
}

/// SVI's fixed point and Störmer–Verlet run a constant-mass sum of terms in O(n): on the FPUT
/// chain of 2000 particles the fixed point ends where sparse Newton on the same stage
/// equations does (`svi-newton`: another solver, with the exact Jacobian), and Verlet where a
/// hand-written kick–drift–kick loop over the chain's force does, to round-off; at n = 10⁵
/// both run without any n × n matrix (the dense check lets them through; 80 GB would not
/// fit).
#[test]
fn one_implementation_runs_constant_mass_chains_of_any_size() {
    use svi::method::any::AnyMethod;
    use svi::{Solver, StormerVerlet, Svi};
    let chain = |n: usize| {
        let mut model = Fput::default();
        model.set_parameter("n", n as f64).unwrap();
        model.set_parameter("beta", 0.5).unwrap();
        model
    };
    let model = chain(2000);
    let (t0, q0, v0) = model.initial_state();
    let h = 0.5 * model.default_step();
    let run = |method: AnyMethod, steps: usize| {
        Integrator::new(Terms(model.clone()), method)
            .run_from_velocity(
                t0,
                q0.clone(),
                v0.clone(),
                h,
                t0 + h * steps as f64,
                &mut (),
            )
            .unwrap()
    };
    let fixed_point = run(AnyMethod::Svi(Svi::new(7).with_quadrature(6)), 20);
    let newton = run(
        AnyMethod::Svi(Svi::new(7).with_quadrature(6).with_solver(Solver::Newton)),
        20,
    );
    assert_eq!(fixed_point.statistics.factorizations, 0);
    assert!(newton.statistics.factorizations > 0);
    let scale = fixed_point.last.q.amax().max(fixed_point.last.p.amax());
    let gap = (&fixed_point.last.q - &newton.last.q)
        .amax()
        .max((&fixed_point.last.p - &newton.last.p).amax());
    assert!(gap <= 1e-12 * scale, "svi: {gap:e} (scale {scale})");
    // Verlet against kick–drift–kick by hand (unit masses), 50 steps.
    let verlet = run(AnyMethod::StormerVerlet(StormerVerlet::default()), 50);
    let (mut q, mut p) = (q0.clone(), v0.clone());
    let mut force = DVector::zeros(q.len());
    for _ in 0..50 {
        model.force_into(0.0, &q, &p, &mut force);
        p.axpy(0.5 * h, &force, 1.0);
        q.axpy(h, &p, 1.0);
        model.force_into(0.0, &q, &p, &mut force);
        p.axpy(0.5 * h, &force, 1.0);
    }
    let gap = (&verlet.last.q - &q)
        .amax()
        .max((&verlet.last.p - &p).amax());
    assert!(gap <= 1e-12 * scale, "verlet: {gap:e}");
    // n = 10⁵: a few steps, each O(n).
    let model = chain(100_000);
    let (t0, q0, v0) = model.initial_state();
    let h = model.default_step();
    for method in [
        AnyMethod::Svi(Svi::new(5)),
        AnyMethod::StormerVerlet(StormerVerlet::default()),
    ] {
        let run = Integrator::new(Terms(model.clone()), method)
            .run_from_velocity(t0, q0.clone(), v0.clone(), h, t0 + 3.0 * h, &mut ())
            .unwrap();
        assert_eq!(run.statistics.steps, 3);
        assert!(run.last.q.iter().all(|x| x.is_finite()));
    }
}

/// Sparse Newton serves every implicit method of ℝᴺ on a sum of terms whose mass matrix
/// depends on q̇: on the relativistic chain of 10⁴ particles (where a dense Newton matrix,
/// (2·10⁴)² entries and more, would be refused), SVI 7/6 keeps the energy to round-off, and
/// midpoint, trapezoid, both symplectic Euler
/// methods, Störmer–Verlet (its implicit path) and SC (its equations in implicit form, one
/// symbolic analysis per run) end where SVI does to within their discretisation errors (the
/// particles move 0.8 per unit time; a wrong residual or momentum update would be off by
/// O(h)).
#[test]
fn sparse_newton_runs_every_implicit_method_on_a_relativistic_chain_of_any_size() {
    use svi::method::any::AnyMethod;
    use svi::model::local::LocalLagrangianExt;
    use svi::{Svi, VariationalIntegrator};
    let mut model = RelativisticChain::default();
    model.set_parameter("n", 10_000.0).unwrap();
    let (t0, q0, v0) = model.initial_state();
    let (h, steps) = (0.1, 10);
    let t_end = t0 + h * steps as f64;
    let generic = |method: AnyMethod| {
        Integrator::new(Terms(model.clone()), method)
            .run_from_velocity(t0, q0.clone(), v0.clone(), h, t_end, &mut ())
            .unwrap()
    };
    let reference = generic(AnyMethod::Svi(Svi::new(7).with_quadrature(6)));
    assert_eq!(reference.statistics.steps, steps);
    // SVI 7/6 (order 12) keeps the energy to round-off.
    let energy = |q: &DVector<f64>, v: &DVector<f64>| LocalLagrangianExt::energy(&model, t0, q, v);
    let (start, end) = (
        energy(&q0, &v0),
        energy(&reference.last.q, &reference.last.v),
    );
    assert!(
        (end - start).abs() <= 1e-12 * start.abs(),
        "{start} → {end}"
    );
    let moved = (&reference.last.q - &q0).amax();
    assert!(moved > 0.7, "moved {moved}");
    // Measured: 2.7e-11 (midpoint) and 5.3e-11 (the others).
    for method in [
        AnyMethod::Midpoint(VariationalIntegrator::new(svi::Midpoint)),
        AnyMethod::Trapezoid(VariationalIntegrator::new(svi::Trapezoid)),
        AnyMethod::SymplecticEuler(VariationalIntegrator::new(svi::SymplecticEuler)),
        AnyMethod::AdjointSymplecticEuler(VariationalIntegrator::new(svi::AdjointSymplecticEuler)),
        AnyMethod::StormerVerlet(svi::StormerVerlet::default()),
        AnyMethod::SpectralCollocation(svi::SpectralCollocation::new(6)),
    ] {
        let name = Method::<Dyn>::info(&method).name;
        let run = generic(method);
        let gap = (&run.last.q - &reference.last.q).amax();
        assert!(gap <= 1e-9, "{name}: {gap:e}");
        assert_eq!(run.statistics.analyses, 1, "{name}");
    }
}

/// The non-symplectic reference methods run the relativistic chain of 10⁴ particles term by
/// term (the acceleration −M⁻¹R(0) with the sparse mass matrix, implicit Euler by sparse
/// Newton; differentiating the whole L would take O(n⁴) a step): halving the step divides
/// their error against SVI 7/6 by 2 (the Euler methods) and 16 (RK4), with one symbolic
/// analysis per run.
#[test]
fn reference_methods_run_a_relativistic_chain_of_any_size_at_their_order() {
    use svi::Svi;
    use svi::method::any::AnyMethod;
    use svi::method::reference::{ExplicitEuler, ImplicitEuler, RungeKutta4};
    let mut model = RelativisticChain::default();
    model.set_parameter("n", 10_000.0).unwrap();
    let (t0, q0, _) = model.initial_state();
    // Neighbours moving apart at up to c/2 (the default mode 1 barely stretches a spring over
    // so short a run): every spring works.
    let v0 = DVector::from_fn(q0.len(), |i, _| 0.5 * (0.9 * i as f64).sin());
    let t_end = t0 + 0.4;
    let run = |method: AnyMethod, h: f64| {
        Integrator::new(Terms(model.clone()), method)
            .run_from_velocity(t0, q0.clone(), v0.clone(), h, t_end, &mut ())
            .unwrap()
    };
    let reference = run(AnyMethod::Svi(Svi::new(7).with_quadrature(6)), 0.05).last;
    for (method, order) in [
        (AnyMethod::ExplicitEuler(ExplicitEuler), 1.0),
        (AnyMethod::ImplicitEuler(ImplicitEuler::default()), 1.0),
        (AnyMethod::RungeKutta4(RungeKutta4), 4.0),
    ] {
        let name = Method::<Dyn>::info(&method).name;
        let [coarse, fine] = [0.1, 0.05].map(|h| {
            let end = run(method.clone(), h);
            assert_eq!(end.statistics.analyses, 1, "{name}");
            (&end.last.q - &reference.q).amax()
        });
        let observed = (coarse / fine).log2();
        println!("{name}: {coarse:e} → {fine:e}, order {observed:.2}");
        assert!(
            (observed - order).abs() <= 0.25,
            "{name}: {coarse:e} → {fine:e}"
        );
    }
}
