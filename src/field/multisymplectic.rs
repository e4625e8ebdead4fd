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

use crate::error::{Error, require_finite};
use crate::field::mesh::Mesh;
use crate::linalg::sparse::{LinearSolver, Pattern, SparseLu};
use crate::linalg::{Singular, invert_small};
use crate::model::density::{
    Boundary, DensityStructure, Jet, LagrangianDensity, LagrangianDensityExt,
};
use nalgebra::{DVector, SMatrix, SVector};

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

/// A quadrature point of the reference cell [0, 1]² with the bilinear shape functions there.
#[derive(Debug, Clone, Copy)]
struct Node {
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
    fn new(xi: f64, tau: f64, weight: f64, dx: f64, dt: f64) -> Self {
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
type CellHessian<const C: usize> = [[SMatrix<f64, C, C>; 4]; 4];

/// The multisymplectic variational integrator of a [`LagrangianDensity`] on a [`Mesh`].
#[derive(Debug, Clone)]
pub struct Multisymplectic<F, const C: usize> {
    density: F,
    mesh: Mesh<C>,
    options: MultisymplecticOptions,
    nodes: Vec<Node>,
}

/// Sums over one slab: the corner derivatives of L_d scattered to the nodes, and the slab's
/// energy and momentum.
struct Slab<const C: usize> {
    bottom: Vec<SVector<f64, C>>,
    top: Vec<SVector<f64, C>>,
    energy: f64,
    momentum: f64,
}

/// The two first variations of the multisymplectic check: values at the current level, at
/// the next, and their discrete momenta.
struct Variations<const C: usize> {
    current: [Vec<SVector<f64, C>>; 2],
    next: [Vec<SVector<f64, C>>; 2],
    momentum: [Vec<SVector<f64, C>>; 2],
    cells: Vec<CellHessian<C>>,
    /// δR of both variations (scratch).
    sums: [Vec<SVector<f64, C>>; 2],
    residual_max: f64,
}

/// The linear system of one level: the block-tridiagonal pattern of ∂(DEL at level j)/∂u^{j+1}
/// over the free nodes, its values, the solver (analysed once) and a right-hand side.
struct LevelSystem {
    pattern: Pattern,
    values: Vec<f64>,
    solver: SparseLu,
    rhs: DVector<f64>,
}

impl LevelSystem {
    /// Solve A x = first + second (both restricted to the free nodes) with the last factored
    /// A; x stays in `rhs`.
    fn solve<const C: usize>(
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
    fn solution<const C: usize>(&self, offset: usize) -> SVector<f64, C> {
        self.rhs.fixed_rows::<C>(offset * C).into_owned()
    }
}

impl<F: LagrangianDensity<C>, const C: usize> Multisymplectic<F, C> {
    /// The integrator of `density` on `mesh`.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] `max_iterations` (zero) or `tolerance` (not finite and
    /// positive).
    pub fn new(density: F, mesh: Mesh<C>, options: MultisymplecticOptions) -> Result<Self, Error> {
        if options.max_iterations == 0 {
            return Err(Error::invalid("max_iterations", "must be at least 1"));
        }
        if !(options.tolerance.is_finite() && options.tolerance > 0.0) {
            return Err(Error::invalid(
                "tolerance",
                format!("{:?} must be finite and positive", options.tolerance),
            ));
        }
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

    /// The pattern of one level's Jacobian (free nodes × their neighbours, C × C blocks),
    /// analysed once.
    fn level_system(&self) -> Result<LevelSystem, Error> {
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

    /// The corner nodes of cell `cell` ([`Mesh::cell_corners`]) and their values, the bottom
    /// two from level `lower`, the top two from `upper`.
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
    fn slab(
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
    fn cell_hessians(
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
    fn cell_hessian(
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

    /// Write ∂(p^j + Σ D_{0|1} L_d)/∂u^{j+1} (bottom corner rows, top corner columns, free
    /// nodes only) into the system's values, from the cells' Hessians.
    fn assemble(&self, cells: &[CellHessian<C>], system: &mut LevelSystem) {
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

    /// Solve p^j + Σ D_{0|1} L_d(u^j, u^{j+1}) = 0 for u^{j+1} (`next`, holding the starting
    /// value) by simplified Newton, the Jacobian taken at the starting value. Returns the
    /// iterations.
    #[allow(clippy::too_many_arguments)]
    fn newton(
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

    /// The two first variations at level 0: V = (sin θ, Δx cos θ), W = (cos 3θ, Δx sin 2θ) in
    /// θ = 2π(x − a)/(b − a), zero on held nodes.
    fn initial_variations(&self) -> Variations<C> {
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
    fn propagate_variations(
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
