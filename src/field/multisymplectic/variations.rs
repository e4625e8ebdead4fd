//! The multisymplectic check: two first variations carried through the linearised level map
//! and the discrete multisymplectic conservation law measured at every free node of every
//! level (see [`crate::field`]).

use super::Multisymplectic;
use super::cell::CellHessian;
use super::level_system::LevelSystem;
use crate::error::Error;
use crate::field::mesh::Mesh;
use crate::linalg::sparse::LinearSolver;
use crate::model::density::LagrangianDensity;
use nalgebra::{SMatrix, SVector};

/// The two first variations of the multisymplectic check: values at the current level, at
/// the next, and their discrete momenta.
pub(super) struct Variations<const C: usize> {
    current: [Vec<SVector<f64, C>>; 2],
    next: [Vec<SVector<f64, C>>; 2],
    momentum: [Vec<SVector<f64, C>>; 2],
    cells: Vec<CellHessian<C>>,
    /// δR of both variations (scratch).
    sums: [Vec<SVector<f64, C>>; 2],
    pub(super) residual_max: f64,
}

impl<F: LagrangianDensity<C>, const C: usize> Multisymplectic<F, C> {
    /// The two first variations at level 0: V = (sin θ, Δx cos θ), W = (cos 3θ, Δx sin 2θ) in
    /// θ = 2π(x − a)/(b − a), zero on held nodes.
    pub(super) fn initial_variations(&self) -> Variations<C> {
        let mesh = &self.mesh;
        let points = mesh.points();
        let zero = vec![SVector::<f64, C>::zeros(); points];
        let mut variations = Variations {
            current: [zero.clone(), zero.clone()],
            next: [zero.clone(), zero.clone()],
            momentum: [zero.clone(), zero.clone()],
            sums: [zero.clone(), zero],
            cells: vec![[[SMatrix::zeros(); 4]; 4]; mesh.cells()],
            residual_max: 0.0,
        };
        let domain = mesh.domain();
        for n in mesh.free_nodes() {
            let theta = 2.0 * std::f64::consts::PI * (mesh.x(n) - domain.left()) / domain.length();
            let profile = |c: usize, f: fn(f64) -> f64, k: f64| f(k * theta + c as f64);
            variations.current[0][n] = SVector::from_fn(|c, _| profile(c, f64::sin, 1.0));
            variations.momentum[0][n] =
                SVector::from_fn(|c, _| profile(c, f64::cos, 1.0)) * mesh.dx();
            variations.current[1][n] = SVector::from_fn(|c, _| profile(c, f64::cos, 3.0));
            variations.momentum[1][n] =
                SVector::from_fn(|c, _| profile(c, f64::sin, 2.0)) * mesh.dx();
        }
        variations
    }

    /// Carry both variations over slab [t, t + Δt] with the linearised level map and measure
    /// the conservation law at the free nodes of level j (see [`crate::field`]):
    /// r_n = W_n · δR_n(V) − V_n · δR_n(W), δR_n(V) = δp_n(V) + Σ_{cells at n} Σ_l D_{k(n)} D_l L_d V_l.
    pub(super) fn propagate_variations(
        &self,
        level: usize,
        t: f64,
        current: &[SVector<f64, C>],
        next: &[SVector<f64, C>],
        variations: &mut Variations<C>,
        system: &mut LevelSystem,
    ) -> Result<(), Error> {
        let mesh = &self.mesh;
        self.cell_hessians(t, current, next, &mut variations.cells);
        self.assemble(&variations.cells, system);
        system
            .solver
            .factor(&system.pattern, &system.values)
            .map_err(|_| Error::SingularMatrix { step: level, t })?;
        let Variations {
            current: values,
            next: upper,
            momentum,
            cells,
            sums,
            residual_max,
        } = variations;
        // δR(V) with the next level's variation zero; the next level's variation solves
        // δR(V) = 0.
        for which in 0..2 {
            upper[which].iter_mut().for_each(|v| *v = SVector::zeros());
            linearised(
                mesh,
                cells,
                &values[which],
                &upper[which],
                [0, 1],
                &mut sums[which],
            );
            system
                .solve(mesh, &momentum[which], &sums[which])
                .map_err(|_| Error::SingularMatrix { step: level, t })?;
            for (offset, n) in mesh.free_nodes().enumerate() {
                upper[which][n] = -system.solution::<C>(offset);
            }
        }
        // The law at level j, then the momenta δp^{j+1} = Σ D_{2|3} D_l L_d V_l.
        for which in 0..2 {
            linearised(
                mesh,
                cells,
                &values[which],
                &upper[which],
                [0, 1],
                &mut sums[which],
            );
            for n in mesh.free_nodes() {
                sums[which][n] += momentum[which][n];
            }
        }
        for n in mesh.free_nodes() {
            let r = values[1][n].dot(&sums[0][n]) - values[0][n].dot(&sums[1][n]);
            *residual_max = residual_max.max(r.abs());
        }
        // The next level's pair, each rescaled to unit max norm (with its momentum: the law
        // is bilinear, and a multiple of a first variation is one) so that growing variations
        // neither overflow nor inflate the round-off of the residual.
        for which in 0..2 {
            linearised(
                mesh,
                cells,
                &values[which],
                &upper[which],
                [2, 3],
                &mut momentum[which],
            );
            std::mem::swap(&mut values[which], &mut upper[which]);
            let size = values[which].iter().map(|v| v.amax()).fold(0.0, f64::max);
            if size > 0.0 {
                values[which]
                    .iter_mut()
                    .chain(momentum[which].iter_mut())
                    .for_each(|v| *v /= size);
            }
        }
        Ok(())
    }
}

/// Σ_{cells} Σ_l D_k D_l L_d V_l for the two corners k in `rows` (bottom 0, 1 or top 2, 3)
/// of every cell, scattered to their nodes in `out`; `lower` and `upper` hold V on the
/// cells' two levels.
fn linearised<const C: usize>(
    mesh: &Mesh<C>,
    cells: &[CellHessian<C>],
    lower: &[SVector<f64, C>],
    upper: &[SVector<f64, C>],
    rows: [usize; 2],
    out: &mut [SVector<f64, C>],
) {
    out.iter_mut().for_each(|v| *v = SVector::zeros());
    for (cell, hessian) in cells.iter().enumerate() {
        let nodes = mesh.cell_corners(cell);
        let values = [
            lower[nodes[0]],
            lower[nodes[1]],
            upper[nodes[2]],
            upper[nodes[3]],
        ];
        for k in rows {
            for (l, value) in values.iter().enumerate() {
                out[nodes[k]] += hessian[k][l] * value;
            }
        }
    }
}
