//! One cell of the mesh: the quadrature points of the reference cell with the bilinear
//! shape functions there, the corner derivatives D_k L_d of every cell of a slab scattered to
//! the nodes with the slab's energy and momentum, and the cell Hessians D_k D_l L_d (Leok
//! §5.1.3).

use super::Multisymplectic;
use crate::model::density::{Jet, LagrangianDensity, LagrangianDensityExt};
use nalgebra::{SMatrix, SVector};

/// A quadrature point of the reference cell [0, 1]² with the bilinear shape functions there.
#[derive(Debug, Clone, Copy)]
pub(super) struct Node {
    /// ξ (space) and τ (time) in the reference cell.
    xi: f64,
    tau: f64,
    /// The weight times ΔxΔt.
    weight: f64,
    /// φ_k, ∂_t φ_k = ∂_τφ_k / Δt and ∂_x φ_k = ∂_ξφ_k / Δx for the corners k = 0 … 3.
    phi: [f64; 4],
    d_t: [f64; 4],
    d_x: [f64; 4],
}

impl Node {
    pub(super) fn new(xi: f64, tau: f64, weight: f64, dx: f64, dt: f64) -> Self {
        Node {
            xi,
            tau,
            weight: weight * dx * dt,
            phi: [
                (1.0 - xi) * (1.0 - tau),
                xi * (1.0 - tau),
                (1.0 - xi) * tau,
                xi * tau,
            ],
            d_t: [-(1.0 - xi) / dt, -xi / dt, (1.0 - xi) / dt, xi / dt],
            d_x: [-(1.0 - tau) / dx, (1.0 - tau) / dx, -tau / dx, tau / dx],
        }
    }

    /// The jet of the bilinear interpolant of the corner values here.
    fn jet<const C: usize>(&self, corners: &[SVector<f64, C>; 4]) -> Jet<C> {
        let mut jet = Jet {
            u: SVector::zeros(),
            u_t: SVector::zeros(),
            u_x: SVector::zeros(),
        };
        for (k, value) in corners.iter().enumerate() {
            jet.u += value * self.phi[k];
            jet.u_t += value * self.d_t[k];
            jet.u_x += value * self.d_x[k];
        }
        jet
    }
}

/// The second derivatives D_k D_l L_d of one cell's discrete Lagrangian, 4 × 4 blocks.
pub(super) type CellHessian<const C: usize> = [[SMatrix<f64, C, C>; 4]; 4];

/// Sums over one slab: the corner derivatives of L_d scattered to the nodes, and the slab's
/// energy and momentum.
pub(super) struct Slab<const C: usize> {
    pub(super) bottom: Vec<SVector<f64, C>>,
    pub(super) top: Vec<SVector<f64, C>>,
    pub(super) energy: f64,
    pub(super) momentum: f64,
}

impl<F: LagrangianDensity<C>, const C: usize> Multisymplectic<F, C> {
    /// The corner nodes of cell `cell`
    /// ([`Mesh::cell_corners`](crate::field::mesh::Mesh::cell_corners)) and their values, the
    /// bottom two from level `lower`, the top two from `upper`.
    fn corners(
        &self,
        cell: usize,
        lower: &[SVector<f64, C>],
        upper: &[SVector<f64, C>],
    ) -> ([usize; 4], [SVector<f64, C>; 4]) {
        let nodes = self.mesh.cell_corners(cell);
        (
            nodes,
            [
                lower[nodes[0]],
                lower[nodes[1]],
                upper[nodes[2]],
                upper[nodes[3]],
            ],
        )
    }

    /// One pass over slab [t, t + Δt]: D_k L_d of every cell scattered to its corners
    /// (bottom: k = 0, 1; top: k = 2, 3), the energy and the momentum.
    pub(super) fn slab(
        &self,
        t: f64,
        lower: &[SVector<f64, C>],
        upper: &[SVector<f64, C>],
        out: &mut Slab<C>,
    ) {
        let mesh = &self.mesh;
        let dt = mesh.dt();
        out.bottom
            .iter_mut()
            .chain(out.top.iter_mut())
            .for_each(|v| *v = SVector::zeros());
        out.energy = 0.0;
        out.momentum = 0.0;
        for cell in 0..mesh.cells() {
            let (nodes, corners) = self.corners(cell, lower, upper);
            let x = mesh.x(nodes[0]);
            let mut derivative = [SVector::<f64, C>::zeros(); 4];
            for node in &self.nodes {
                let jet = node.jet(&corners);
                let g = self
                    .density
                    .gradient(x + node.xi * mesh.dx(), t + node.tau * dt, &jet);
                for (k, d) in derivative.iter_mut().enumerate() {
                    *d += (g.u * node.phi[k] + g.u_t * node.d_t[k] + g.u_x * node.d_x[k])
                        * node.weight;
                }
                out.energy += node.weight / dt * g.energy(&jet);
                out.momentum += node.weight / dt * g.momentum(&jet);
            }
            out.bottom[nodes[0]] += derivative[0];
            out.bottom[nodes[1]] += derivative[1];
            out.top[nodes[2]] += derivative[2];
            out.top[nodes[3]] += derivative[3];
        }
    }

    /// D_k D_l L_d of every cell of slab [t, t + Δt] ([`Self::cell_hessian`]).
    pub(super) fn cell_hessians(
        &self,
        t: f64,
        lower: &[SVector<f64, C>],
        upper: &[SVector<f64, C>],
        out: &mut [CellHessian<C>],
    ) {
        for (cell, hessian) in out.iter_mut().enumerate() {
            *hessian = self.cell_hessian(cell, t, lower, upper);
        }
    }

    /// D_k D_l L_d of cell `cell` of slab [t, t + Δt]:
    /// ΔxΔt Σ_q w_q Σ_{a,b} s_k^a ∂²ℒ/∂a∂b s_l^b with s_k = (φ_k, ∂_tφ_k, ∂_xφ_k).
    pub(super) fn cell_hessian(
        &self,
        cell: usize,
        t: f64,
        lower: &[SVector<f64, C>],
        upper: &[SVector<f64, C>],
    ) -> CellHessian<C> {
        let mesh = &self.mesh;
        let (nodes, corners) = self.corners(cell, lower, upper);
        let x = mesh.x(nodes[0]);
        let mut hessian = [[SMatrix::zeros(); 4]; 4];
        for node in &self.nodes {
            let jet = node.jet(&corners);
            let h = self
                .density
                .hessian(x + node.xi * mesh.dx(), t + node.tau * mesh.dt(), &jet)
                .blocks;
            let s = |k: usize| [node.phi[k], node.d_t[k], node.d_x[k]];
            for (k, row) in hessian.iter_mut().enumerate() {
                for (l, block) in row.iter_mut().enumerate() {
                    let (sk, sl) = (s(k), s(l));
                    for a in 0..3 {
                        for b in 0..3 {
                            let factor = node.weight * sk[a] * sl[b];
                            if factor != 0.0 {
                                *block += h[a][b] * factor;
                            }
                        }
                    }
                }
            }
        }
        hessian
    }
}
