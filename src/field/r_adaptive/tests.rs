//! Unit tests of the r-adaptive integrator on a private sine-Gordon density (the zoo's
//! models are not visible from unit tests).

use super::*;
use crate::field::mesh::Mesh;
use crate::field::multisymplectic::{Multisymplectic, MultisymplecticOptions};
use crate::model::density::DensityStructure;
use crate::scalar::Scalar;
use std::f64::consts::PI;

/// ℒ = ½u_t² − ½u_x² − (1 − cos u).
#[derive(Debug, Clone, Copy)]
struct SineGordon;

impl LagrangianDensity<1> for SineGordon {
    const STRUCTURE: DensityStructure = DensityStructure::ConstantMass;
    fn density<D: Scalar>(
        &self,
        _x: f64,
        _t: f64,
        u: &SVector<D, 1>,
        u_t: &SVector<D, 1>,
        u_x: &SVector<D, 1>,
    ) -> D {
        (u_t[0] * u_t[0] - u_x[0] * u_x[0]) * 0.5 - (D::from(1.0) - u[0].cos())
    }
}

/// (u, u_t) of the kink of speed v centred at x₀ at time t.
fn kink(v: f64, x0: f64, x: f64, t: f64) -> (f64, f64) {
    let gamma = 1.0 / (1.0 - v * v).sqrt();
    let xi = gamma * (x - x0 - v * t);
    (4.0 * xi.exp().atan(), -2.0 * gamma * v / xi.cosh())
}

fn wide() -> Domain {
    Domain::new(-20.0, 20.0).unwrap()
}

fn held(left: f64, right: f64) -> Boundary<1> {
    Boundary::Dirichlet {
        left: SVector::from([left]),
        right: SVector::from([right]),
    }
}

fn options(nodes: usize, dt: f64, monitor: Monitor) -> RAdaptiveOptions {
    RAdaptiveOptions {
        nodes,
        dt,
        monitor,
        ..RAdaptiveOptions::default()
    }
}

/// The largest nodal error against the kink over all levels.
fn kink_error(
    v: f64,
    x0: f64,
    options: RAdaptiveOptions,
    levels: usize,
) -> Result<(AdaptiveRun<1>, f64), Error> {
    let integrator = RAdaptive::new(SineGordon, wide(), held(0.0, 2.0 * PI), options)?;
    let mut error = 0.0f64;
    let run = integrator.run(
        0.0,
        |x| {
            let (u, u_t) = kink(v, x0, x, 0.0);
            (SVector::from([u]), SVector::from([u_t]))
        },
        levels,
        |_, t, x, u| {
            for (x, u) in x.iter().zip(u) {
                error = error.max((u[0] - kink(v, x0, *x, t).0).abs());
            }
        },
    )?;
    Ok((run, error))
}

#[test]
fn a_uniform_monitor_reduces_to_the_uniform_integrator() {
    for quadrature in [CellQuadrature::Trapezoid, CellQuadrature::Midpoint] {
        let (nodes, dt, levels) = (81, 0.25, 40);
        let mut adaptive = options(nodes, dt, Monitor::Uniform);
        adaptive.quadrature = quadrature;
        let integrator =
            RAdaptive::new(SineGordon, wide(), held(0.0, 2.0 * PI), adaptive).unwrap();
        let initial = |x: f64| {
            let (u, u_t) = kink(0.5, -5.0, x, 0.0);
            (SVector::from([u]), SVector::from([u_t]))
        };
        let mut moving = Vec::new();
        let run = integrator
            .run(0.0, initial, levels, |_, _, x, u| {
                moving.push((x.to_vec(), u.to_vec()))
            })
            .unwrap();
        let mesh = Mesh::new(wide(), nodes, dt, held(0.0, 2.0 * PI)).unwrap();
        let mut uniform_options = MultisymplecticOptions::default();
        uniform_options.quadrature = quadrature;
        let uniform = Multisymplectic::new(SineGordon, mesh.clone(), uniform_options).unwrap();
        let mut gap = 0.0f64;
        let mut drift = 0.0f64;
        let reference = uniform
            .run(0.0, initial, levels, |j, _, u| {
                let (x, v) = &moving[j];
                for (n, (x, v)) in x.iter().zip(v).enumerate() {
                    drift = drift.max((x - mesh.x(n)).abs());
                    gap = gap.max((v[0] - u[n][0]).abs());
                }
            })
            .unwrap();
        let energy_gap = run
            .energy
            .iter()
            .zip(&reference.energy)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        println!("{quadrature:?}: field gap {gap:e}, node drift {drift:e}, energy gap {energy_gap:e}");
        assert!(gap < 1e-10 && drift < 1e-12 && energy_gap < 1e-9);
    }
}

#[test]
fn the_fast_kink_on_a_moving_mesh() {
    let monitor = Monitor::ArcLength { scale: 1.0 };
    let mut o = options(81, 0.1, monitor);
    o.smoothing = 2.0;
    let (run, error) = kink_error(0.99, -10.0, o, 20).unwrap();
    println!(
        "error {error:e}, smallest width {:e}, iterations {}, factorizations {}",
        run.smallest_width, run.newton_iterations, run.factorizations
    );
    println!("{:?}", &run.positions.last().unwrap());
}

#[test]
fn debug_initial_mesh() {
    let o = options(21, 0.1, Monitor::ArcLength { scale: 1.0 });
    let integrator = RAdaptive::new(SineGordon, wide(), held(0.0, 2.0 * PI), o).unwrap();
    let x: Vec<f64> = (0..21).map(|i| -20.0 + 2.0 * i as f64).collect();
    let u: Vec<SVector<f64, 1>> = x.iter().map(|&x| SVector::from([kink(0.99, -10.0, x, 0.0).0])).collect();
    let mut g = vec![0.0; 10];
    for i in 1..20 {
        let value = integrator.constraint_gradient(i, &x, &u, &mut g);
        println!("{i} {value:e} {g:?}");
    }
}
