//! The mesh equations: the monitor ω of a cell, the smoothed equidistribution constraint
//! g_i(q) = h̄ (ω_i ñ_{i−1} − ω_{i−1} ñ_i) at interior node i (h̄ the mean cell width), its
//! gradient by `Dual64` sweeps over the five nodes it involves, and the initial mesh.

use super::{Monitor, RAdaptive};
use crate::error::Error;
use crate::linalg::sparse::{LinearSolver, Pattern, SparseLu};
use crate::model::density::LagrangianDensity;
use crate::scalar::Scalar;
use nalgebra::{DVector, SVector};
use num_dual::Dual64;

/// The nodes g_i involves: i − 2 … i + 2 (clamped to the mesh).
pub(super) const WINDOW: usize = 5;

impl<F: LagrangianDensity<C>, const C: usize> RAdaptive<F, C> {
    /// g_i at node i of a mesh of `last` cells, with node positions `x(k)` and values `u(k)`
    /// of any scalar type.
    pub(super) fn constraint<D: Scalar>(
        &self,
        i: usize,
        last: usize,
        x: &impl Fn(usize) -> D,
        u: &impl Fn(usize) -> SVector<D, C>,
    ) -> D {
        let kappa = self.options.smoothing;
        let clamp = |k: isize| k.clamp(0, last as isize - 1) as usize;
        let concentration = |k: usize| (x(k + 1) - x(k)).recip();
        let smoothed = |k: usize| {
            let (before, after) = (clamp(k as isize - 1), clamp(k as isize + 1));
            let centre = concentration(k);
            centre
                - (concentration(after) - centre * 2.0 + concentration(before))
                    * (kappa * (kappa + 1.0))
        };
        let monitor = |k: usize| self.cell_monitor(k, last, x, u);
        let mean = self.domain.length() / last as f64;
        (monitor(i) * smoothed(i - 1) - monitor(i - 1) * smoothed(i)) * mean
    }

    /// The monitor ω_k of cell k (see [`Monitor`]).
    pub(super) fn cell_monitor<D: Scalar>(
        &self,
        k: usize,
        last: usize,
        x: &impl Fn(usize) -> D,
        u: &impl Fn(usize) -> SVector<D, C>,
    ) -> D {
        let clamp = |k: isize| k.clamp(0, last as isize - 1) as usize;
        let slope = |k: usize| {
            let n = (x(k + 1) - x(k)).recip();
            (u(k + 1) - u(k)).map(|v| v * n)
        };
        match self.options.monitor {
            Monitor::Uniform => D::from(1.0),
            Monitor::ArcLength { scale } => {
                let s = slope(k);
                (s.dot(&s) * scale + 1.0).sqrt()
            }
            Monitor::Curvature { scale, curvature } => {
                let s = slope(k);
                let (before, after) = (clamp(k as isize - 1), clamp(k as isize + 1));
                let centre = |k: usize| (x(k) + x(k + 1)) * 0.5;
                let gap = (centre(after) - centre(before)).recip();
                let c = (slope(after) - slope(before)).map(|v| v * gap);
                (s.dot(&s) * scale + c.dot(&c) * curvature + 1.0).sqrt()
            }
        }
    }

    /// g_i(x, u) and its gradient in the free nodes' variables: entry (m − i + 2)(C + 1) + v
    /// of `out` is ∂g_i/∂(variable v of node m) (v = C for x_m), zero for nodes off the mesh
    /// or held.
    pub(super) fn constraint_gradient(
        &self,
        i: usize,
        x: &[f64],
        u: &[SVector<f64, C>],
        out: &mut [f64],
    ) -> f64 {
        let last = x.len() - 1;
        let mut value = 0.0;
        out.iter_mut().for_each(|v| *v = 0.0);
        for offset in 0..WINDOW {
            let Some(m) = (i + offset).checked_sub(2).filter(|&m| m >= 1 && m < last) else {
                continue;
            };
            for v in 0..=C {
                let lifted_x = |k: usize| {
                    let mut d = Dual64::from_re(x[k]);
                    if k == m && v == C {
                        d.eps = 1.0;
                    }
                    d
                };
                let lifted_u = |k: usize| {
                    let mut d = u[k].map(Dual64::from_re);
                    if k == m && v < C {
                        d[v].eps = 1.0;
                    }
                    d
                };
                let g = self.constraint(i, last, &lifted_x, &lifted_u);
                value = g.re;
                out[offset * (C + 1) + v] = g.eps;
            }
        }
        value
    }

    /// The mesh that equidistributes the initial field `field(x)` (nodal values u_i =
    /// field(x_i)), from [`super::RAdaptiveOptions::initial_mesh`] or the uniform mesh:
    /// first de Boor's fixed point without smoothing (the piecewise-constant monitor of the
    /// current mesh equidistributed exactly, a few times), then damped Newton on
    /// G(x) = g(field(x), x) = 0, smoothing included, to an increment below 10⁻¹³ of the
    /// domain's length. (Holding the values at the nodes while they move would have no
    /// solution for a front steeper than the starting mesh.) The Jacobian of G takes
    /// ∂g/∂u (num-dual) times a central difference of `field`: it only steers the iteration,
    /// the residual G is exact.
    pub(super) fn initial_mesh(
        &self,
        t0: f64,
        field: &impl Fn(f64) -> Result<SVector<f64, C>, Error>,
    ) -> Result<Vec<f64>, Error> {
        let nodes = self.options.nodes;
        let last = nodes - 1;
        let (a, length) = (self.domain.left(), self.domain.length());
        let mut x: Vec<f64> = match &self.options.initial_mesh {
            Some(mesh) => mesh.clone(),
            None => (0..nodes)
                .map(|i| a + length * i as f64 / last as f64)
                .collect(),
        };
        x[0] = a;
        x[last] = self.domain.right();
        let sample = |x: &[f64]| -> Result<Vec<SVector<f64, C>>, Error> {
            x.iter().map(|&position| field(position)).collect()
        };
        // de Boor: equidistribute the monitor of the current mesh, held as a function of x.
        for _ in 0..30 {
            let u = sample(&x)?;
            let lift = |k: usize| x[k];
            let values = |k: usize| u[k];
            let mut cumulative = vec![0.0; nodes];
            for k in 0..last {
                let weight = self.cell_monitor(k, last, &lift, &values);
                cumulative[k + 1] = cumulative[k] + weight * (x[k + 1] - x[k]);
            }
            let total = cumulative[last];
            let mut fresh = x.clone();
            let mut k = 0;
            for (i, position) in fresh.iter_mut().enumerate().take(last).skip(1) {
                let target = total * i as f64 / last as f64;
                while cumulative[k + 1] < target && k + 1 < last {
                    k += 1;
                }
                let share = (target - cumulative[k]) / (cumulative[k + 1] - cumulative[k]);
                *position = x[k] + share.clamp(0.0, 1.0) * (x[k + 1] - x[k]);
            }
            let change = fresh
                .iter()
                .zip(&x)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            if !fresh.windows(2).all(|pair| pair[1] > pair[0]) {
                break;
            }
            x = fresh;
            if change <= 1e-3 * length / last as f64 {
                break;
            }
        }
        // Newton on G(x) = g(field(x), x).
        let free = last - 1;
        let mut entries = Vec::with_capacity(free * WINDOW);
        for r in 0..free {
            for s in r.saturating_sub(2)..(r + 3).min(free) {
                entries.push((r, s));
            }
        }
        let pattern = Pattern::new(free, &entries)?;
        let mut solver = SparseLu::default();
        solver.analyse(&pattern)?;
        let mut values = vec![0.0; pattern.len()];
        let mut rhs = DVector::zeros(free);
        let mut gradient = vec![0.0; WINDOW * (C + 1)];
        let failure = |iterations, residual| Error::NonConvergence {
            step: 0,
            t: t0,
            iterations,
            residual,
        };
        let cap = 4 * self.options.max_iterations;
        let delta = 1e-6 * length / last as f64;
        let mut increment = f64::INFINITY;
        for _ in 0..cap {
            let u = sample(&x)?;
            let mut slope = vec![SVector::<f64, C>::zeros(); nodes];
            for i in 1..last {
                slope[i] = (field(x[i] + delta)? - field(x[i] - delta)?) / (2.0 * delta);
            }
            values.iter_mut().for_each(|v| *v = 0.0);
            for i in 1..last {
                rhs[i - 1] = self.constraint_gradient(i, &x, &u, &mut gradient);
                for offset in 0..WINDOW {
                    let Some(m) = (i + offset).checked_sub(2).filter(|&m| m >= 1 && m < last)
                    else {
                        continue;
                    };
                    let mut d = gradient[offset * (C + 1) + C];
                    for c in 0..C {
                        d += gradient[offset * (C + 1) + c] * slope[m][c];
                    }
                    if let Some(slot) = pattern.slot(i - 1, m - 1) {
                        values[slot] = d;
                    }
                }
            }
            solver
                .factor(&pattern, &values)
                .map_err(|_| failure(0, f64::INFINITY))?;
            solver
                .solve_in_place(&mut rhs)
                .map_err(|_| failure(0, f64::INFINITY))?;
            // Damped: no cell shrinks below half its width in one iteration.
            let mut theta = 1.0f64;
            let shift = |i: usize| if i == 0 || i == last { 0.0 } else { rhs[i - 1] };
            for k in 0..last {
                let shrink = shift(k + 1) - shift(k);
                if shrink > 0.5 * (x[k + 1] - x[k]) {
                    theta = theta.min(0.5 * (x[k + 1] - x[k]) / shrink);
                }
            }
            for i in 1..last {
                x[i] -= theta * rhs[i - 1];
            }
            increment = rhs.amax();
            if theta == 1.0 && increment <= 1e-13 * length {
                return Ok(x);
            }
        }
        Err(failure(cap, increment))
    }
}
