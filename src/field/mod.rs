//! Field theories in 1 + 1 dimensions: multisymplectic variational integrators of a
//! [`LagrangianDensity`](crate::model::density::LagrangianDensity) ℒ(x, t, u, u_t, u_x)
//! (Leok, *Generalized Variational Integrators*, §5.1.2–5.1.3 and the multisymplectic part of
//! §5.2; Marsden, Patrick & Shkoller, *Multisymplectic geometry, variational integrators, and
//! nonlinear PDEs*, 1998).
//!
//! # The discrete action (§5.1.3)
//! On the uniform mesh x_i = a + iΔx, t_j = t₀ + jΔt ([`mesh`]) the field is the bilinear
//! interpolant of the nodal values u_{i,j} ≈ u(x_i, t_j): tensor products φ_{i,j}(x, t) of hat
//! functions, each supported on the four cells around its node. The action splits into cells,
//!
//! S_d = Σ_{i,j} L_d(u_{i,j}, u_{i+1,j}, u_{i,j+1}, u_{i+1,j+1}),
//! L_d = ∫_{x_i}^{x_{i+1}} ∫_{t_j}^{t_{j+1}} ℒ(j¹ Σ_{a,b} u_{a,b} φ_{a,b}) dt dx,
//!
//! with the cell integral replaced by a quadrature rule
//! ([`multisymplectic::CellQuadrature`]). Varying u_{i,j} alone gives the discrete
//! Euler–Lagrange equation of §5.1.3, four terms from the four cells around the node:
//!
//! D₁L_d(cell i,j) + D₂L_d(cell i−1,j) + D₃L_d(cell i,j−1) + D₄L_d(cell i−1,j−1) = 0
//!
//! (corners numbered 1 = (i, j), 2 = (i + 1, j), 3 = (i, j + 1), 4 = (i + 1, j + 1) of each
//! cell). It couples three time levels; it is solved for level j + 1 given levels j and
//! j − 1, the latter folded into a discrete momentum p^j_n = D₃L_d + D₄L_d of the cells below.
//!
//! # Which quadrature
//! The trapezoidal rule on the four corners ([`multisymplectic::CellQuadrature::Trapezoid`],
//! the default) evaluates ℒ where the bilinear interpolant's jet is exact edge differences,
//! and for ℒ = ½|u_t|² − ½|u_x|² − V(u) the DEL becomes
//!
//! (u_{i,j+1} − 2u_{i,j} + u_{i,j−1})/Δt² − (u_{i+1,j} − 2u_{i,j} + u_{i−1,j})/Δx² + V'(u_{i,j}) = 0,
//!
//! linear in u_{i,j+1} alone: the scheme is explicit (leapfrog), second order, with the
//! stability limit Δt ≤ Δx/c for the wave equation (Δt² (4c²/Δx² + V'') ≤ 4 with a potential).
//! The midpoint rule of Marsden–Patrick–Shkoller
//! ([`multisymplectic::CellQuadrature::Midpoint`]) evaluates ℒ at the cell centre with the
//! averaged value ū and differences averaged over two edges: the box scheme, implicit through
//! V(ū) (its level Jacobian has diagonal blocks −(ΔxΔt/4)·2(1/Δt² + 1/Δx²) and off-diagonal
//! ones (ΔxΔt/4)(1/Δx² − 1/Δt²) for the wave part), unconditionally stable for the wave
//! equation. Both are second order; the trapezoid rule is the default because it is explicit
//! for every density of the form ½ u_tᵀ M u_t + f(x, t, u, u_x) (the
//! [`DensityStructure::ConstantMass`](crate::model::density::DensityStructure) declaration)
//! and needs no linear algebra at all.
//!
//! # The multisymplectic conservation law
//! Let V, W be two first variations of a solution (solutions of the linearised DEL). For one
//! cell put θ_k = D_k L_d du_k and Ω_k = dθ_k, so that
//! Ω_k(V, W) = Σ_l (V_lᵀ D_lD_kL_d W_k − W_lᵀ D_lD_kL_d V_k); since dL_d = Σ_k θ_k,
//! Σ_k Ω_k = ddL_d = 0 in every cell. The DEL at node n says Σ_{cells at n} θ_{k(n)} = 0 on
//! solutions, and its derivative along V and W is the local statement checked here,
//!
//! Σ_{cells at n} Ω_{k(n)}(V, W) = W_n · δR_n(V) − V_n · δR_n(W) = 0,
//! δR_n(V) = Σ_{cells at n} Σ_l D_{k(n)}D_l L_d V_l (the linearised DEL),
//!
//! the discrete conservation of the symplectic structure on the dual cell around each node.
//! Summed over a region, the cell identities Σ_k Ω_k = 0 cancel every interior term and
//! leave the discrete multisymplectic form formula of Marsden–Patrick–Shkoller (the sum of the
//! Ω's of the boundary cells vanishes). For the leapfrog scheme it reads
//! (ω_{i,j+½} − ω_{i,j−½})/Δt − (κ_{i+½,j} − κ_{i−½,j})/Δx = 0 with
//! ω_{i,j+½} = (W_{i,j}V_{i,j+1} − V_{i,j}W_{i,j+1})/Δt and
//! κ_{i+½,j} = (W_{i,j}V_{i+1,j} − V_{i,j}W_{i+1,j})/Δx (Bridges & Reich 2001).
//! [`multisymplectic::Multisymplectic::run`] propagates V and W through the linearised level
//! map (the level Jacobian, factored by faer's sparse LU), rescaling each to unit max norm
//! at every level (a multiple of a first variation is one; without it, variations that grow
//! secularly along a breather's phase would inflate the round-off of the bilinear residual),
//! and reports the largest |residual| over all nodes and levels.
//!
//! # Energy and momentum
//! For a density independent of x and t, the discrete energy of slab [t_j, t_{j+1}] is the
//! cell quadrature of the energy density π·u_t − ℒ (π = ∂ℒ/∂u_t) divided by Δt, and the
//! momentum that of −π·u_x; neither is conserved exactly, both stay within O(Δx² + Δt²) of
//! their initial values with no drift (the scheme is multisymplectic).

//!
//! # Moving meshes (§5.6)
//! [`r_adaptive`] pulls the action back to a regular computational mesh mapped to x by node
//! positions that are unknowns too, fixed by an equidistribution principle imposed as
//! constraints with multipliers in the discrete action: the r-adaptive multisymplectic
//! integrator, with nodes that cluster where the field is steep.
//!
//! # Pseudospectral integrators (§5.8)
//! A complex field ψ = a + ib on a periodic domain with a density first order in time,
//! ℒ = c(b a_t − a b_t) − W(x, t, u, u_x) (Schrödinger, cubic NLS): a discrete Fourier series
//! in space ([`fourier`]) and a Galerkin polynomial in time, or the Strang split-step Fourier
//! method for comparison ([`pseudospectral`]).

pub mod fourier;
pub mod mesh;
pub mod multisymplectic;
pub mod pseudospectral;
pub mod r_adaptive;
