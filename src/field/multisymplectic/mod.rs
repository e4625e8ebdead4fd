//! The multisymplectic variational integrator of a 1 + 1 field on a uniform mesh (Leok §5.1.3;
//! Marsden, Patrick & Shkoller 1998): bilinear shape functions, the discrete Lagrangian of each
//! cell by a tensor-product quadrature, and the four-term discrete Euler–Lagrange equation
//! solved level by level. The mathematics is in [`crate::field`]; this file is the solver.
//!
//! # Discrete equations
//! With the corners of cell (i, j) numbered 0 = (i, j), 1 = (i + 1, j), 2 = (i, j + 1),
//! 3 = (i + 1, j + 1) and the quadrature points q of the reference square with weights w_q,
//!
//! D_k L_d = ΔxΔt Σ_q w_q \[φ_k ∂ℒ/∂u + (∂_τφ_k/Δt) ∂ℒ/∂u_t + (∂_ξφ_k/Δx) ∂ℒ/∂u_x\](q),
//!
//! the level map takes (u^j, p^j) to (u^{j+1}, p^{j+1}) by
//!
//! p^j_n + Σ_{cells of slab j at n} D_{0|1} L_d(u^j, u^{j+1}) = 0 (solved for u^{j+1}),
//! p^{j+1}_n = Σ_{cells of slab j at n} D_{2|3} L_d(u^j, u^{j+1}),
//!
//! which is the four-term DEL (§5.1.3) with the two cells below node n folded into the
//! discrete momentum p^j_n, and p⁰_n = Δx ∂ℒ/∂u_t at the initial field (u_x by central
//! differences).
//!
//! # Properties
//! Order 2 in (Δx, Δt) with either [`CellQuadrature`]; multisymplectic (the discrete
//! conservation law of [`crate::field`] holds node by node); energy and momentum bounded with
//! no drift for autonomous, x-independent densities. Explicit (leapfrog) for
//! [`DensityStructure::ConstantMass`] densities with [`CellQuadrature::Trapezoid`], under the
//! stability limit checked at the initial field; sparse simplified Newton (block-tridiagonal
//! Jacobian, symbolic analysis once per run) otherwise.

mod cell;
mod level_system;
mod variations;

use crate::error::{Error, require_finite};
use crate::field::mesh::Mesh;
use crate::linalg::invert_small;
use crate::model::density::{
    Boundary, DensityStructure, Jet, LagrangianDensity, LagrangianDensityExt,
};
use cell::{Node, Slab};
use nalgebra::{SMatrix, SVector};

/// The quadrature of the cell integral ∫∫ ℒ(j¹ of the bilinear interpolant) dx dt.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum CellQuadrature {
    /// The tensor-product trapezoidal rule: the four corners, weight ¼ each. At a corner the
    /// bilinear interpolant's jet is (u_node, the difference along the cell's vertical edge
    /// there, the difference along its horizontal edge there), so for
    /// ℒ = ½|u_t|² − ½|u_x|² − V(u) the DEL is the leapfrog scheme
    /// (u^{j+1} − 2u^j + u^{j−1})/Δt² − (u_{i+1} − 2u_i + u_{i−1})/Δx² + V'(u_{i,j}) = 0:
    /// explicit. The default.
    #[default]
    Trapezoid,
    /// The midpoint of the cell, weight 1 (Marsden, Patrick & Shkoller 1998): the box
    /// scheme, implicit through V(ū) at the cell centres (a block-tridiagonal Newton system
    /// per level), unconditionally stable for the wave equation.
    Midpoint,
}

/// Options of [`Multisymplectic`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct MultisymplecticOptions {
    /// The cell quadrature.
    pub quadrature: CellQuadrature,
    /// Solve every level by Newton's method even when the scheme is explicit (a reference
    /// for the explicit path).
    pub force_newton: bool,
    /// Iteration cap of Newton's method per level.
    pub max_iterations: usize,
    /// Newton stops when ‖Δu‖∞ ≤ tolerance · (1 + ‖u‖∞).
    pub tolerance: f64,
    /// Propagate two first variations with the linearised level map and measure the discrete
    /// multisymplectic conservation law at every free node of every level
    /// ([`FieldRun::multisymplectic_residual_max`]); costs the Hessian of ℒ at every
    /// quadrature point and one sparse factorisation per level.
    pub multisymplectic_check: bool,
}

impl Default for MultisymplecticOptions {
    fn default() -> Self {
        MultisymplecticOptions {
            quadrature: CellQuadrature::Trapezoid,
            force_newton: false,
            max_iterations: 50,
            tolerance: 1e-13,
            multisymplectic_check: false,
        }
    }
}

/// What a run of [`Multisymplectic::run`] returns.
#[derive(Debug, Clone, PartialEq)]
pub struct FieldRun<const C: usize> {
    /// The field at the last level, node by node.
    pub last: Vec<SVector<f64, C>>,
    /// The discrete energy E^{j+½} = Σ_cells Δx Σ_q w_q (π·u_t − ℒ)(q) of each slab
    /// [t_j, t_{j+1}], j = 0, 1, ….
    pub energy: Vec<f64>,
    /// The discrete momentum P^{j+½} = −Σ_cells Δx Σ_q w_q (π·u_x)(q) of each slab.
    pub momentum: Vec<f64>,
    /// The largest |residual| of the discrete multisymplectic conservation law over all free
    /// nodes and levels, for first variations of unit max norm at each level (see
    /// [`crate::field`]); `None` unless [`MultisymplecticOptions::multisymplectic_check`].
    pub multisymplectic_residual_max: Option<f64>,
    /// Whether the levels were solved explicitly.
    pub explicit: bool,
    /// Newton iterations over the run (0 when explicit).
    pub newton_iterations: usize,
}

/// The multisymplectic variational integrator of a [`LagrangianDensity`] on a [`Mesh`].
#[derive(Debug, Clone)]
pub struct Multisymplectic<F, const C: usize> {
    density: F,
    mesh: Mesh<C>,
    options: MultisymplecticOptions,
    nodes: Vec<Node>,
}

/// The options of a level's Newton iteration: at least one iteration and a finite positive
/// tolerance, else [`Error::InvalidParameter`] `max_iterations` or `tolerance`.
pub(crate) fn check_newton(max_iterations: usize, tolerance: f64) -> Result<(), Error> {
    if max_iterations == 0 {
        return Err(Error::invalid("max_iterations", "must be at least 1"));
    }
    if !(tolerance.is_finite() && tolerance > 0.0) {
        return Err(Error::invalid(
            "tolerance",
            format!("{tolerance:?} must be finite and positive"),
        ));
    }
    Ok(())
}

impl<F: LagrangianDensity<C>, const C: usize> Multisymplectic<F, C> {
    /// The integrator of `density` on `mesh`.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] `max_iterations` (zero) or `tolerance` (not finite and
    /// positive).
    pub fn new(density: F, mesh: Mesh<C>, options: MultisymplecticOptions) -> Result<Self, Error> {
        check_newton(options.max_iterations, options.tolerance)?;
        let (dx, dt) = (mesh.dx(), mesh.dt());
        let nodes = match options.quadrature {
            CellQuadrature::Trapezoid => [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
                .iter()
                .map(|&(xi, tau)| Node::new(xi, tau, 0.25, dx, dt))
                .collect(),
            CellQuadrature::Midpoint => vec![Node::new(0.5, 0.5, 1.0, dx, dt)],
        };
        Ok(Multisymplectic {
            density,
            mesh,
            options,
            nodes,
        })
    }

    /// The mesh.
    pub fn mesh(&self) -> &Mesh<C> {
        &self.mesh
    }

    /// Whether the levels are solved explicitly: a [`DensityStructure::ConstantMass`] density
    /// with [`CellQuadrature::Trapezoid`] (the DEL at node n is then linear in u^{j+1}_n
    /// alone, with the constant coefficient −(Δx/Δt) M), unless
    /// [`MultisymplecticOptions::force_newton`].
    pub fn is_explicit(&self) -> bool {
        F::STRUCTURE == DensityStructure::ConstantMass
            && self.options.quadrature == CellQuadrature::Trapezoid
            && !self.options.force_newton
    }

    /// Run `levels` time levels from t0, starting from the field (u, u_t) = `initial(x)`.
    /// `observe(j, t_j, u^j)` sees every level, the initial one (j = 0) included.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for a non-finite t0 or initial field (`initial`), an
    /// initial field that disagrees with the Dirichlet values (`boundary`), a density that
    /// breaks its [`DensityStructure`] declaration (`structure`), or a time step above the
    /// stability limit of the explicit scheme (`dt`). During the run:
    /// [`Error::NonConvergence`], [`Error::SingularMatrix`] or [`Error::NonFinite`] with the
    /// level index and its time.
    pub fn run(
        &self,
        t0: f64,
        initial: impl Fn(f64) -> (SVector<f64, C>, SVector<f64, C>),
        levels: usize,
        mut observe: impl FnMut(usize, f64, &[SVector<f64, C>]),
    ) -> Result<FieldRun<C>, Error> {
        require_finite("t0", t0)?;
        let mesh = &self.mesh;
        let (points, dx, dt) = (mesh.points(), mesh.dx(), mesh.dt());
        let (mut current, velocity): (Vec<_>, Vec<_>) =
            (0..points).map(|n| initial(mesh.x(n))).unzip();
        for (n, (u, v)) in current.iter().zip(&velocity).enumerate() {
            if !u.iter().chain(v.iter()).all(|x| x.is_finite()) {
                return Err(Error::invalid(
                    "initial",
                    format!("the initial field is not finite at x = {:?}", mesh.x(n)),
                ));
            }
        }
        self.hold_boundary(&mut current)?;
        let jets: Vec<Jet<C>> = (0..points)
            .map(|n| {
                let (left, right) = mesh.neighbours(n);
                Jet {
                    u: current[n],
                    u_t: velocity[n],
                    u_x: (current[right] - current[left]) / (2.0 * dx),
                }
            })
            .collect();
        let explicit = self.is_explicit();
        if F::STRUCTURE == DensityStructure::ConstantMass {
            self.check_initial_structure(t0, &jets, explicit)?;
        }
        let mut momentum: Vec<SVector<f64, C>> = jets
            .iter()
            .enumerate()
            .map(|(n, jet)| self.density.gradient(mesh.x(n), t0, jet).u_t * dx)
            .collect();

        let mut previous = current.clone();
        let mut next = current.clone();
        let mut slab = Slab {
            bottom: vec![SVector::zeros(); points],
            top: vec![SVector::zeros(); points],
            energy: 0.0,
            momentum: 0.0,
        };
        let mut system = if explicit && !self.options.multisymplectic_check {
            None
        } else {
            Some(self.level_system()?)
        };
        // Newton's cell Hessians; explicit: the inverse diagonal blocks of the (constant,
        // block-diagonal) Jacobian instead.
        let (mut cell_hessians, inverse_blocks) = if explicit {
            (Vec::new(), self.inverse_diagonal(t0, &current)?)
        } else {
            (vec![[[SMatrix::zeros(); 4]; 4]; mesh.cells()], Vec::new())
        };
        let mut variations = self
            .options
            .multisymplectic_check
            .then(|| self.initial_variations());
        let mut run = FieldRun {
            last: Vec::new(),
            energy: Vec::with_capacity(levels),
            momentum: Vec::with_capacity(levels),
            multisymplectic_residual_max: None,
            explicit,
            newton_iterations: 0,
        };
        observe(0, t0, &current);
        for level in 0..levels {
            let t = t0 + level as f64 * dt;
            let extrapolate = !explicit && level > 0;
            for n in mesh.free_nodes() {
                next[n] = if extrapolate {
                    current[n] * 2.0 - previous[n]
                } else {
                    current[n]
                };
            }
            if explicit {
                self.slab(t, &current, &next, &mut slab);
                for (offset, n) in mesh.free_nodes().enumerate() {
                    next[n] -= inverse_blocks[offset] * (momentum[n] + slab.bottom[n]);
                }
            } else if let Some(system) = system.as_mut() {
                run.newton_iterations += self.newton(
                    level,
                    t,
                    &current,
                    &mut next,
                    &momentum,
                    &mut slab,
                    system,
                    &mut cell_hessians,
                )?;
            }
            self.slab(t, &current, &next, &mut slab);
            if !next.iter().all(|u| u.iter().all(|x| x.is_finite())) || !slab.energy.is_finite() {
                return Err(Error::NonFinite {
                    what: "field".into(),
                    step: level,
                    t,
                });
            }
            run.energy.push(slab.energy);
            run.momentum.push(slab.momentum);
            if let (Some(variations), Some(system)) = (variations.as_mut(), system.as_mut()) {
                self.propagate_variations(level, t, &current, &next, variations, system)?;
            }
            for n in mesh.free_nodes() {
                momentum[n] = slab.top[n];
            }
            std::mem::swap(&mut previous, &mut current);
            std::mem::swap(&mut current, &mut next);
            observe(level + 1, t + dt, &current);
        }
        run.multisymplectic_residual_max = variations.map(|v| v.residual_max);
        run.last = current;
        Ok(run)
    }

    /// Check the initial field against the Dirichlet values (within 10⁻⁶, relative) and put
    /// them on the end nodes.
    fn hold_boundary(&self, field: &mut [SVector<f64, C>]) -> Result<(), Error> {
        let Boundary::Dirichlet { left, right } = *self.mesh.boundary() else {
            return Ok(());
        };
        let last = field.len() - 1;
        for (node, value, end) in [(0, left, "left"), (last, right, "right")] {
            let gap = (field[node] - value).amax();
            if gap > 1e-6 * (1.0 + value.amax()) {
                return Err(Error::invalid(
                    "boundary",
                    format!(
                        "the initial field at the {end} end, {:?}, differs from the Dirichlet value {:?} by {gap:e}",
                        field[node].as_slice(),
                        value.as_slice()
                    ),
                ));
            }
            field[node] = value;
        }
        Ok(())
    }

    /// Check a [`DensityStructure::ConstantMass`] declaration at the initial jets, and for the
    /// explicit scheme its von Neumann limit Δt² μ ≤ 4, μ the largest eigenvalue of
    /// M⁻¹(4K/Δx² − ∂²ℒ/∂u²) with K = −∂²ℒ/∂u_x² (for the wave equation Δt ≤ Δx/c).
    fn check_initial_structure(
        &self,
        t0: f64,
        jets: &[Jet<C>],
        explicit: bool,
    ) -> Result<(), Error> {
        let mesh = &self.mesh;
        let (dx, dt) = (mesh.dx(), mesh.dt());
        let mut mass = None;
        for n in mesh.free_nodes() {
            let x = mesh.x(n);
            let [[uu, _, _], [tu, tt, tx], [_, _, xx]] =
                self.density.hessian(x, t0, &jets[n]).blocks;
            let scale = 1.0 + tt.amax();
            let reference = *mass.get_or_insert(tt);
            if tu.amax() > 1e-12 * scale
                || tx.amax() > 1e-12 * scale
                || (tt - reference).amax() > 1e-12 * scale
            {
                return Err(Error::invalid(
                    "structure",
                    format!(
                        "the density is declared ConstantMass but ∂²ℒ/∂u_t² is not one constant matrix independent of u and u_x (at x = {x:?})"
                    ),
                ));
            }
            if !explicit {
                continue;
            }
            let Some(inverse) = invert_small(&tt) else {
                return Err(Error::invalid(
                    "structure",
                    format!("∂²ℒ/∂u_t² is singular at x = {x:?}"),
                ));
            };
            let stiffness = inverse * (xx * (-4.0 / (dx * dx)) - uu);
            let mu = largest_eigenvalue(&stiffness);
            if dt * dt * mu > 4.0 * (1.0 + 1e-12) {
                let speed = largest_eigenvalue(&(inverse * -xx)).max(0.0).sqrt();
                return Err(Error::invalid(
                    "dt",
                    format!(
                        "Δt = {dt:?} exceeds the stability limit 2/√μ = {:?} of the explicit scheme at x = {x:?} (wave speed c = {speed:?}, Δx/c = {:?}); take a smaller Δt or the midpoint quadrature",
                        2.0 / mu.sqrt(),
                        dx / speed
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The inverses of the diagonal blocks of the explicit scheme's Jacobian, from the cells
    /// of the first slab with both levels at `field`.
    fn inverse_diagonal(
        &self,
        t0: f64,
        field: &[SVector<f64, C>],
    ) -> Result<Vec<SMatrix<f64, C, C>>, Error> {
        let mesh = &self.mesh;
        let mut diagonal = vec![SMatrix::<f64, C, C>::zeros(); mesh.free_nodes().len()];
        for cell in 0..mesh.cells() {
            let hessian = self.cell_hessian(cell, t0, field, field);
            let (left, right) = mesh.cell_nodes(cell);
            for (k, node) in [(0, left), (1, right)] {
                if let Some(index) = mesh.unknown(node) {
                    diagonal[index] += hessian[k][k + 2];
                }
            }
        }
        diagonal
            .iter()
            .map(|block| {
                invert_small(block).ok_or_else(|| {
                    Error::invalid("structure", "the mass matrix ∂²ℒ/∂u_t² is singular")
                })
            })
            .collect()
    }
}

/// The eigenvalue of largest modulus of a small matrix with real eigenvalues (power
/// iteration; exact for C = 1).
fn largest_eigenvalue<const C: usize>(a: &SMatrix<f64, C, C>) -> f64 {
    if C == 1 {
        return a[(0, 0)];
    }
    let mut v = SVector::<f64, C>::from_fn(|i, _| 1.0 + i as f64 * 0.1);
    let mut lambda = 0.0;
    for _ in 0..200 {
        let w = a * v;
        let norm = w.amax();
        if norm == 0.0 {
            return 0.0;
        }
        lambda = w.dot(&v) / v.dot(&v);
        v = w / norm;
    }
    lambda
}
