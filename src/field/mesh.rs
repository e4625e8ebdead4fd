//! The uniform space-time mesh of a 1 + 1 field: nodes x_i = a + iΔx in space, levels
//! t_j = t₀ + jΔt in time, and what the boundary condition makes of the nodes at the ends.
//!
//! - [`Boundary::Periodic`]: `points` = M nodes x_0 … x_{M−1}, Δx = (b − a)/M, node M is
//!   node 0; M cells per level, and every node is free.
//! - [`Boundary::Dirichlet`]: `points` = M + 1 nodes x_0 = a … x_M = b, Δx = (b − a)/M; M
//!   cells per level, the two end nodes hold the boundary values and nodes 1 … M − 1 are free.
//!
//! Either way a free node has two neighbours and lies in the four cells around it.

use crate::error::{Error, require_finite_entries, require_positive};
use crate::model::density::{Boundary, Domain};

/// The smallest number of nodes a mesh may have (a Dirichlet mesh needs one free node
/// between its ends).
pub const MIN_POINTS: usize = 3;

/// The largest number of nodes in space: 10⁶, which a 2-core machine steps at about 1.5 s a
/// level in 0.6 GB (measured 2026-11-27 for the explicit scheme and for Newton's; 10⁷ nodes
/// took 5 GB and more than 20 s a level).
pub const MAX_POINTS: usize = 1_000_000;

/// A uniform space-time mesh on a [`Domain`] with its [`Boundary`] condition.
#[derive(Debug, Clone, PartialEq)]
pub struct Mesh<const C: usize> {
    domain: Domain,
    points: usize,
    dx: f64,
    dt: f64,
    boundary: Boundary<C>,
}

impl<const C: usize> Mesh<C> {
    /// The mesh of `points` nodes on `domain` with time step `dt` and `boundary`.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] named `points` (fewer than [`MIN_POINTS`] or more than
    /// [`MAX_POINTS`]), `dt` (not finite and positive) or `boundary` (a non-finite Dirichlet
    /// value).
    pub fn new(
        domain: Domain,
        points: usize,
        dt: f64,
        boundary: Boundary<C>,
    ) -> Result<Self, Error> {
        if !(MIN_POINTS..=MAX_POINTS).contains(&points) {
            return Err(Error::invalid(
                "points",
                format!(
                    "{points} nodes in space: a mesh needs from {MIN_POINTS} to {MAX_POINTS} nodes"
                ),
            ));
        }
        require_positive("dt", dt)?;
        if let Boundary::Dirichlet { left, right } = &boundary {
            require_finite_entries("boundary.left", left.iter())
                .and(require_finite_entries("boundary.right", right.iter()))
                .map_err(|e| Error::invalid("boundary", format!("Dirichlet value: {e}")))?;
        }
        let cells = match boundary {
            Boundary::Periodic => points,
            Boundary::Dirichlet { .. } => points - 1,
        };
        let dx = domain.length() / cells as f64;
        require_positive("dx", dx)?;
        Ok(Mesh {
            domain,
            points,
            dx,
            dt,
            boundary,
        })
    }

    /// The number of nodes in space.
    pub fn points(&self) -> usize {
        self.points
    }

    /// The number of cells per time level (= the number of nodes for a periodic mesh, one
    /// less for a Dirichlet mesh).
    pub fn cells(&self) -> usize {
        match self.boundary {
            Boundary::Periodic => self.points,
            Boundary::Dirichlet { .. } => self.points - 1,
        }
    }

    /// Δx.
    pub fn dx(&self) -> f64 {
        self.dx
    }

    /// Δt.
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// The domain.
    pub fn domain(&self) -> Domain {
        self.domain
    }

    /// The boundary condition.
    pub fn boundary(&self) -> &Boundary<C> {
        &self.boundary
    }

    /// The position x_i of node i.
    pub fn x(&self, node: usize) -> f64 {
        self.domain.left() + node as f64 * self.dx
    }

    /// The left and right nodes of cell `cell` (the right node of the last periodic cell is
    /// node 0).
    pub fn cell_nodes(&self, cell: usize) -> (usize, usize) {
        (cell, (cell + 1) % self.points)
    }

    /// The nodes at the corners of cell `cell` on its two levels, in the order of the cell's
    /// discrete Lagrangian: 0 = bottom left, 1 = bottom right, 2 = top left, 3 = top right.
    pub fn cell_corners(&self, cell: usize) -> [usize; 4] {
        let (left, right) = self.cell_nodes(cell);
        [left, right, left, right]
    }

    /// The free nodes (those not held by a Dirichlet condition), ascending.
    pub fn free_nodes(&self) -> std::ops::Range<usize> {
        match self.boundary {
            Boundary::Periodic => 0..self.points,
            Boundary::Dirichlet { .. } => 1..self.points - 1,
        }
    }

    /// The index of free node `node` among the free nodes; `None` for a held node.
    pub fn unknown(&self, node: usize) -> Option<usize> {
        let free = self.free_nodes();
        free.contains(&node).then(|| node - free.start)
    }

    /// The left and right neighbours of free node `node` (wrapping around a periodic mesh).
    pub fn neighbours(&self, node: usize) -> (usize, usize) {
        (
            (node + self.points - 1) % self.points,
            (node + 1) % self.points,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::SVector;

    fn unit() -> Domain {
        Domain::new(0.0, 1.0).unwrap()
    }

    #[test]
    fn periodic_and_dirichlet_meshes_place_their_nodes() {
        let periodic = Mesh::<1>::new(unit(), 4, 0.1, Boundary::Periodic).unwrap();
        assert_eq!((periodic.dx(), periodic.cells()), (0.25, 4));
        assert_eq!(periodic.cell_nodes(3), (3, 0));
        assert_eq!(periodic.neighbours(0), (3, 1));
        assert_eq!(
            (periodic.free_nodes(), periodic.unknown(3)),
            (0..4, Some(3))
        );
        let held = Boundary::Dirichlet {
            left: SVector::from([0.0]),
            right: SVector::from([1.0]),
        };
        let dirichlet = Mesh::<1>::new(unit(), 5, 0.1, held).unwrap();
        assert_eq!((dirichlet.dx(), dirichlet.cells()), (0.25, 4));
        assert_eq!(dirichlet.x(4), 1.0);
        assert_eq!(dirichlet.free_nodes(), 1..4);
        assert_eq!(
            (dirichlet.unknown(0), dirichlet.unknown(2)),
            (None, Some(1))
        );
    }

    /// The name an error carries, or a panic if there is none.
    fn error_name<T: std::fmt::Debug>(result: Result<T, Error>) -> String {
        match result {
            Err(Error::InvalidParameter { name, .. }) => name,
            other => panic!("expected an invalid parameter, got {other:?}"),
        }
    }

    #[test]
    fn bad_meshes_and_boundaries_are_named_errors() {
        for points in [0, 1, 2, MAX_POINTS + 1] {
            assert_eq!(
                error_name(Mesh::<1>::new(unit(), points, 0.1, Boundary::Periodic)),
                "points"
            );
        }
        for dt in [0.0, -0.1, f64::NAN, f64::INFINITY] {
            assert_eq!(
                error_name(Mesh::<1>::new(unit(), 10, dt, Boundary::Periodic)),
                "dt"
            );
        }
        let bad = Boundary::Dirichlet {
            left: SVector::from([0.0, f64::NAN]),
            right: SVector::from([0.0, 0.0]),
        };
        assert_eq!(error_name(Mesh::<2>::new(unit(), 10, 0.1, bad)), "boundary");
        // A domain so short that Δx underflows to zero.
        let tiny = Domain::new(0.0, 5e-324).unwrap();
        assert_eq!(
            error_name(Mesh::<1>::new(tiny, 10, 0.1, Boundary::Periodic)),
            "dx"
        );
    }
}
