//! One computational cell: the pulled-back discrete Lagrangian
//! L_d = Δt Σ_q w_q x_ξ ℒ(x, t, ũ, (ũ_τ − u_x x_τ)/Δt, ũ_ξ/x_ξ) of the bilinear ũ and x, written
//! once for any [`Scalar`], and its derivatives in the corner values q_k = (u_k, x_k) by
//! num-dual sweeps.

use super::RAdaptive;
use crate::field::multisymplectic::CellQuadrature;
use crate::model::density::{Jet, LagrangianDensity, LagrangianDensityExt};
use crate::scalar::Scalar;
use nalgebra::SVector;
use num_dual::{Dual64, HyperDual64};

/// A quadrature point of the reference cell [0, 1]² with the bilinear shape functions and
/// their reference derivatives there.
#[derive(Debug, Clone, Copy)]
pub(super) struct QuadraturePoint {
    tau: f64,
    weight: f64,
    phi: [f64; 4],
    d_xi: [f64; 4],
    d_tau: [f64; 4],
}

/// The quadrature points of `quadrature` (corners 0 = (0, 0), 1 = (1, 0), 2 = (0, 1),
/// 3 = (1, 1) in (ξ, τ)).
pub(super) fn quadrature_points(quadrature: CellQuadrature) -> Vec<QuadraturePoint> {
    let point = |xi: f64, tau: f64, weight: f64| QuadraturePoint {
        tau,
        weight,
        phi: [
            (1.0 - xi) * (1.0 - tau),
            xi * (1.0 - tau),
            (1.0 - xi) * tau,
            xi * tau,
        ],
        d_xi: [-(1.0 - tau), 1.0 - tau, -tau, tau],
        d_tau: [-(1.0 - xi), -xi, 1.0 - xi, xi],
    };
    match quadrature {
        CellQuadrature::Trapezoid => [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
            .iter()
            .map(|&(xi, tau)| point(xi, tau, 0.25))
            .collect(),
        CellQuadrature::Midpoint => vec![point(0.5, 0.5, 1.0)],
        // CellQuadrature is exhaustive today; a future rule would fall back to the midpoint.
        #[allow(unreachable_patterns)]
        _ => vec![point(0.5, 0.5, 1.0)],
    }
}

/// The corner values of one cell: field and position at the four corners.
#[derive(Debug, Clone, Copy)]
pub(super) struct Corners<const C: usize> {
    pub(super) u: [SVector<f64, C>; 4],
    pub(super) x: [f64; 4],
}

/// The physical jet and Jacobian x_ξ at a quadrature point, for any scalar.
struct PointJet<D: Scalar, const C: usize> {
    x: D,
    x_xi: D,
    u: SVector<D, C>,
    u_t: SVector<D, C>,
    u_x: SVector<D, C>,
}

impl QuadraturePoint {
    /// ũ, x and the physical jet u_x = ũ_ξ/x_ξ, u_t = (ũ_τ − u_x x_τ)/Δt here.
    fn jet<D: Scalar, const C: usize>(
        &self,
        u: &[SVector<D, C>; 4],
        x: &[D; 4],
        dt: f64,
    ) -> PointJet<D, C> {
        let zero = D::from(0.0);
        let (mut position, mut x_xi, mut x_tau) = (zero, zero, zero);
        let mut value = SVector::<D, C>::from_element(zero);
        let mut u_xi = value;
        let mut u_tau = value;
        for k in 0..4 {
            position += x[k] * self.phi[k];
            x_xi += x[k] * self.d_xi[k];
            x_tau += x[k] * self.d_tau[k];
            for c in 0..C {
                value[c] += u[k][c] * self.phi[k];
                u_xi[c] += u[k][c] * self.d_xi[k];
                u_tau[c] += u[k][c] * self.d_tau[k];
            }
        }
        let inverse = x_xi.recip();
        let u_x = u_xi.map(|v| v * inverse);
        let mut u_t = u_tau;
        for c in 0..C {
            u_t[c] = (u_tau[c] - u_x[c] * x_tau) * (1.0 / dt);
        }
        PointJet {
            x: position,
            x_xi,
            u: value,
            u_t,
            u_x,
        }
    }
}

impl<F: LagrangianDensity<C>, const C: usize> RAdaptive<F, C> {
    /// L_d of one cell of slab [t, t + Δt] at corner values of any scalar type.
    fn cell_lagrangian<D: Scalar>(&self, t: f64, u: &[SVector<D, C>; 4], x: &[D; 4]) -> D {
        let dt = self.options.dt;
        let mut total = D::from(0.0);
        for point in &self.points {
            let jet = point.jet(u, x, dt);
            // ℒ does not depend on x explicitly (checked by `run`): its real part is passed.
            let density =
                self.density
                    .density(jet.x.re(), t + point.tau * dt, &jet.u, &jet.u_t, &jet.u_x);
            total += density * jet.x_xi * (point.weight * dt);
        }
        total
    }

    /// D_k L_d for the 4(C + 1) corner variables (variable v of corner k at k(C + 1) + v,
    /// v = C for x): one `Dual64` sweep each.
    pub(super) fn cell_gradient(&self, t: f64, corners: &Corners<C>, out: &mut [f64]) {
        let lift_u = corners.u.map(|v| v.map(Dual64::from_re));
        let lift_x = corners.x.map(Dual64::from_re);
        for k in 0..4 {
            for v in 0..=C {
                let (mut u, mut x) = (lift_u, lift_x);
                if v < C {
                    u[k][v].eps = 1.0;
                } else {
                    x[k].eps = 1.0;
                }
                out[k * (C + 1) + v] = self.cell_lagrangian(t, &u, &x).eps;
            }
        }
    }

    /// The block D_{bottom} D_{top} L_d: entry (a, b) = ∂²L_d/∂z_a∂z_{2(C+1)+b} for the
    /// bottom variables a and the top variables b, row-major; one `HyperDual64` sweep each.
    pub(super) fn cell_hessian(&self, t: f64, corners: &Corners<C>, out: &mut [f64]) {
        let half = 2 * (C + 1);
        let lift_u = corners.u.map(|v| v.map(HyperDual64::from_re));
        let lift_x = corners.x.map(HyperDual64::from_re);
        for a in 0..half {
            for b in 0..half {
                let (mut u, mut x) = (lift_u, lift_x);
                let (ka, va) = (a / (C + 1), a % (C + 1));
                let (kb, vb) = (2 + b / (C + 1), b % (C + 1));
                if va < C {
                    u[ka][va].eps1 = 1.0;
                } else {
                    x[ka].eps1 = 1.0;
                }
                if vb < C {
                    u[kb][vb].eps2 = 1.0;
                } else {
                    x[kb].eps2 = 1.0;
                }
                out[a * half + b] = self.cell_lagrangian(t, &u, &x).eps1eps2;
            }
        }
    }

    /// The cell's share of the slab energy Σ_q w_q x_ξ (π·u_t − ℒ) and momentum
    /// −Σ_q w_q x_ξ π·u_x.
    pub(super) fn cell_energy(&self, t: f64, corners: &Corners<C>) -> (f64, f64) {
        let dt = self.options.dt;
        let (mut energy, mut momentum) = (0.0, 0.0);
        for point in &self.points {
            let jet = point.jet(&corners.u, &corners.x, dt);
            let physical = Jet {
                u: jet.u,
                u_t: jet.u_t,
                u_x: jet.u_x,
            };
            let g = self.density.gradient(jet.x, t + point.tau * dt, &physical);
            energy += point.weight * jet.x_xi * g.energy(&physical);
            momentum += point.weight * jet.x_xi * g.momentum(&physical);
        }
        (energy, momentum)
    }
}
