//! The linear system of one level: the sparse block-tridiagonal Jacobian of the discrete
//! Euler–Lagrange equation in the next level's free nodes, analysed once per run and
//! factored per level, and the simplified Newton iteration that solves an implicit level.

use super::Multisymplectic;
use super::cell::{CellHessian, Slab};
use crate::error::Error;
use crate::field::mesh::Mesh;
use crate::linalg::Singular;
use crate::linalg::sparse::{LinearSolver, Pattern, SparseLu};
use crate::model::density::LagrangianDensity;
use nalgebra::{DVector, SVector};

/// The linear system of one level: the block-tridiagonal pattern of ∂(DEL at level j)/∂u^{j+1}
/// over the free nodes, its values, the solver (analysed once) and a right-hand side.
pub(super) struct LevelSystem {
    pub(super) pattern: Pattern,
    pub(super) values: Vec<f64>,
    pub(super) solver: SparseLu,
    rhs: DVector<f64>,
}

impl LevelSystem {
    /// Solve A x = first + second (both restricted to the free nodes) with the last factored
    /// A; x stays in `rhs`.
    pub(super) fn solve<const C: usize>(
        &mut self,
        mesh: &Mesh<C>,
        first: &[SVector<f64, C>],
        second: &[SVector<f64, C>],
    ) -> Result<(), Singular> {
        for (offset, n) in mesh.free_nodes().enumerate() {
            self.rhs
                .fixed_rows_mut::<C>(offset * C)
                .copy_from(&(first[n] + second[n]));
        }
        self.solver.solve_in_place(&mut self.rhs)
    }

    /// The block of the last solution belonging to free node number `offset`.
    pub(super) fn solution<const C: usize>(&self, offset: usize) -> SVector<f64, C> {
        self.rhs.fixed_rows::<C>(offset * C).into_owned()
    }
}

impl<F: LagrangianDensity<C>, const C: usize> Multisymplectic<F, C> {
    /// The pattern of one level's Jacobian (free nodes × their neighbours, C × C blocks),
    /// analysed once.
    pub(super) fn level_system(&self) -> Result<LevelSystem, Error> {
        let mesh = &self.mesh;
        let unknowns = mesh.free_nodes().len() * C;
        let mut entries = Vec::with_capacity(unknowns * 3 * C);
        for n in mesh.free_nodes() {
            let (left, right) = mesh.neighbours(n);
            for m in [left, n, right] {
                if let (Some(row), Some(col)) = (mesh.unknown(n), mesh.unknown(m)) {
                    for a in 0..C {
                        for b in 0..C {
                            entries.push((row * C + a, col * C + b));
                        }
                    }
                }
            }
        }
        let pattern = Pattern::new(unknowns, &entries)?;
        let mut solver = SparseLu::default();
        solver.analyse(&pattern)?;
        Ok(LevelSystem {
            values: vec![0.0; pattern.len()],
            pattern,
            solver,
            rhs: DVector::zeros(unknowns),
        })
    }

    /// Write ∂(p^j + Σ D_{0|1} L_d)/∂u^{j+1} (bottom corner rows, top corner columns, free
    /// nodes only) into the system's values, from the cells' Hessians.
    pub(super) fn assemble(&self, cells: &[CellHessian<C>], system: &mut LevelSystem) {
        system.values.iter_mut().for_each(|v| *v = 0.0);
        for (cell, hessian) in cells.iter().enumerate() {
            let nodes = self.mesh.cell_corners(cell);
            for k in 0..2 {
                for l in 2..4 {
                    let (Some(row), Some(col)) =
                        (self.mesh.unknown(nodes[k]), self.mesh.unknown(nodes[l]))
                    else {
                        continue;
                    };
                    for a in 0..C {
                        for b in 0..C {
                            if let Some(slot) = system.pattern.slot(row * C + a, col * C + b) {
                                system.values[slot] += hessian[k][l][(a, b)];
                            }
                        }
                    }
                }
            }
        }
    }

    /// Solve p^j + Σ D_{0|1} L_d(u^j, u^{j+1}) = 0 for u^{j+1} (`next`, holding the starting
    /// value) by simplified Newton, the Jacobian taken at the starting value. Returns the
    /// iterations.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn newton(
        &self,
        level: usize,
        t: f64,
        current: &[SVector<f64, C>],
        next: &mut [SVector<f64, C>],
        momentum: &[SVector<f64, C>],
        slab: &mut Slab<C>,
        system: &mut LevelSystem,
        cells: &mut [CellHessian<C>],
    ) -> Result<usize, Error> {
        let mesh = &self.mesh;
        self.cell_hessians(t, current, next, cells);
        self.assemble(cells, system);
        system
            .solver
            .factor(&system.pattern, &system.values)
            .map_err(|_| Error::SingularMatrix { step: level, t })?;
        let mut increment = f64::INFINITY;
        for iteration in 1..=self.options.max_iterations {
            self.slab(t, current, next, slab);
            system
                .solve(mesh, momentum, &slab.bottom)
                .map_err(|_| Error::SingularMatrix { step: level, t })?;
            let mut size = 0.0f64;
            for (offset, n) in mesh.free_nodes().enumerate() {
                next[n] -= system.solution::<C>(offset);
                size = size.max(next[n].amax());
            }
            increment = system.rhs.amax();
            if !increment.is_finite() {
                break;
            }
            if increment <= self.options.tolerance * (1.0 + size) {
                return Ok(iteration);
            }
        }
        Err(Error::NonConvergence {
            step: level,
            t,
            iterations: self.options.max_iterations,
            residual: increment,
        })
    }
}
