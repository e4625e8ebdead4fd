//! One level: the Newton system of the discrete Euler–Lagrange equations in (u, x) with the
//! constraint forces λ^j ∇g(q^j) and the constraints g(q^{j+1}) = 0, in the unknowns
//! z_r = (u^{j+1}_i, x^{j+1}_i, λ^j_i) of the interior nodes i = r + 1 (block size C + 2,
//! rows in the same order: DEL in u, DEL in x, g). The Jacobian couples nodes at most two
//! apart; its pattern is analysed once per run, and it is refactored (simplified Newton) when
//! the iteration contracts slowly.

use super::RAdaptive;
use super::cell::Corners;
use super::equidistribution::WINDOW;
use crate::error::Error;
use crate::linalg::sparse::{LinearSolver, Pattern, SparseLu};
use crate::model::density::LagrangianDensity;
use nalgebra::{DVector, SVector};

/// The contraction ‖Δ_k‖/‖Δ_{k−1}‖ above which the level Jacobian is refactored.
const REFACTOR_CONTRACTION: f64 = 0.1;

/// The state at a level: positions, values, the multipliers of the last level solved, and
/// the discrete momenta p = (p_u, p_x) of the nodes.
#[derive(Debug, Clone)]
pub(super) struct State<const C: usize> {
    pub(super) x: Vec<f64>,
    pub(super) u: Vec<SVector<f64, C>>,
    pub(super) multipliers: Vec<f64>,
    pub(super) momentum_u: Vec<SVector<f64, C>>,
    pub(super) momentum_x: Vec<f64>,
}

/// The level system and its scratch, sized once per run.
pub(super) struct LevelSolver<const C: usize> {
    pattern: Pattern,
    values: Vec<f64>,
    solver: SparseLu,
    rhs: DVector<f64>,
    /// ∇g_m(q^j) of every interior node m ([`WINDOW`](C + 1) entries each).
    old_gradients: Vec<f64>,
    /// ∇g_i(q^{j+1}) at the current iterate.
    new_gradients: Vec<f64>,
    gradient: Vec<f64>,
    hessian: Vec<f64>,
    next_x: Vec<f64>,
    next_u: Vec<SVector<f64, C>>,
    pub(super) iterations: usize,
    pub(super) factorizations: usize,
}

impl<const C: usize> LevelSolver<C> {
    /// The solver of a mesh of `nodes` nodes.
    pub(super) fn new<F: LagrangianDensity<C>>(
        _integrator: &RAdaptive<F, C>,
        nodes: usize,
    ) -> Result<Self, Error> {
        let free = nodes - 2;
        let block = C + 2;
        let mut entries = Vec::with_capacity(free * WINDOW * block * block);
        for r in 0..free {
            for s in r.saturating_sub(2)..(r + 3).min(free) {
                for a in 0..block {
                    for b in 0..block {
                        entries.push((r * block + a, s * block + b));
                    }
                }
            }
        }
        let pattern = Pattern::new(free * block, &entries)?;
        let mut solver = SparseLu::default();
        solver.analyse(&pattern)?;
        Ok(LevelSolver {
            values: vec![0.0; pattern.len()],
            pattern,
            solver,
            rhs: DVector::zeros(free * block),
            old_gradients: vec![0.0; nodes * WINDOW * (C + 1)],
            new_gradients: vec![0.0; nodes * WINDOW * (C + 1)],
            gradient: vec![0.0; 4 * (C + 1)],
            hessian: vec![0.0; 4 * (C + 1) * (C + 1)],
            next_x: vec![0.0; nodes],
            next_u: vec![SVector::zeros(); nodes],
            iterations: 0,
            factorizations: 0,
        })
    }

    /// Add `value` at (row, col) of the Jacobian (both unknown indices).
    fn add(&mut self, row: usize, col: usize, value: f64) {
        if let Some(slot) = self.pattern.slot(row, col) {
            self.values[slot] += value;
        }
    }

    /// Solve level j (slab [t, t + Δt]) and move `state` to level j + 1; `previous` holds
    /// level j − 1 for the extrapolated start (and receives level j). Returns the slab's
    /// energy and momentum.
    pub(super) fn step<F: LagrangianDensity<C>>(
        &mut self,
        integrator: &RAdaptive<F, C>,
        level: usize,
        t: f64,
        state: &mut State<C>,
        previous: &mut Option<(Vec<f64>, Vec<SVector<f64, C>>)>,
    ) -> Result<(f64, f64), Error> {
        let nodes = state.x.len();
        let last = nodes - 1;
        let width = WINDOW * (C + 1);
        for m in 1..last {
            let (x, u) = (&state.x, &state.u);
            integrator.constraint_gradient(
                m,
                x,
                u,
                &mut self.old_gradients[m * width..(m + 1) * width],
            );
        }
        // Start from q^{j+1} extrapolated from q^j and q^{j−1} (λ^j from λ^{j−1}); should
        // Newton's iteration fail from there (a front that turns within a step, the first
        // level of a steep front), once more from q^{j+1} = q^j, λ^j = 0.
        let mut multipliers = state.multipliers.clone();
        let mut outcome = Ok(());
        for attempt in 0..2 {
            if attempt == 1 {
                if outcome.is_ok() {
                    break;
                }
                self.next_x.copy_from_slice(&state.x);
                self.next_u.copy_from_slice(&state.u);
                multipliers.iter_mut().for_each(|m| *m = 0.0);
            }
            outcome = self.newton(
                integrator,
                level,
                t,
                state,
                previous.as_ref(),
                attempt,
                &mut multipliers,
            );
        }
        outcome?;
        // The momenta p^{j+1} = Σ D_{2|3} L_d, and the slab's energy and momentum.
        let (mut energy, mut momentum) = (0.0, 0.0);
        state
            .momentum_u
            .iter_mut()
            .for_each(|p| *p = SVector::zeros());
        state.momentum_x.iter_mut().for_each(|p| *p = 0.0);
        for k in 0..last {
            let corners = self.corners(state, k);
            integrator.cell_gradient(t, &corners, &mut self.gradient);
            for (corner, node) in [(2, k), (3, k + 1)] {
                for c in 0..C {
                    state.momentum_u[node][c] += self.gradient[corner * (C + 1) + c];
                }
                state.momentum_x[node] += self.gradient[corner * (C + 1) + C];
            }
            let (e, p) = integrator.cell_energy(t, &corners);
            energy += e;
            momentum += p;
        }
        if !energy.is_finite() || self.next_u.iter().any(|u| !u.iter().all(|v| v.is_finite())) {
            return Err(Error::NonFinite {
                what: "field".into(),
                step: level,
                t,
            });
        }
        let old = previous.get_or_insert_with(|| (Vec::new(), Vec::new()));
        old.0.clone_from(&state.x);
        old.1.clone_from(&state.u);
        state.x.copy_from_slice(&self.next_x);
        state.u.copy_from_slice(&self.next_u);
        state.multipliers = multipliers;
        Ok((energy, momentum))
    }

    /// Newton's iteration of one level from the start of `attempt` (0: extrapolated, 1: the
    /// caller's), leaving q^{j+1} in `next_x`, `next_u` and λ^j in `multipliers`.
    // Nodes index several parallel arrays (positions, values, multipliers, rows).
    #[allow(clippy::too_many_arguments, clippy::needless_range_loop)]
    fn newton<F: LagrangianDensity<C>>(
        &mut self,
        integrator: &RAdaptive<F, C>,
        level: usize,
        t: f64,
        state: &State<C>,
        previous: Option<&(Vec<f64>, Vec<SVector<f64, C>>)>,
        attempt: usize,
        multipliers: &mut [f64],
    ) -> Result<(), Error> {
        let nodes = state.x.len();
        let last = nodes - 1;
        let block = C + 2;
        let width = WINDOW * (C + 1);
        let options = integrator.options();
        if attempt == 0 {
            // Start: q^{j+1} extrapolated from q^j and q^{j−1}; λ^j from λ^{j−1}.
            match previous {
                Some((x, u)) => {
                    for i in 0..nodes {
                        self.next_x[i] = 2.0 * state.x[i] - x[i];
                        self.next_u[i] = state.u[i] * 2.0 - u[i];
                    }
                }
                None => {
                    self.next_x.copy_from_slice(&state.x);
                    self.next_u.copy_from_slice(&state.u);
                }
            }
            self.next_x[0] = state.x[0];
            self.next_x[last] = state.x[last];
            self.next_u[0] = state.u[0];
            self.next_u[last] = state.u[last];
        }
        let mut refresh = true;
        let mut last_increment = f64::INFINITY;
        let mut converged = false;
        let mut increment = f64::INFINITY;
        for _ in 0..options.max_iterations {
            self.iterations += 1;
            self.rhs.fill(0.0);
            if refresh {
                self.values.iter_mut().for_each(|v| *v = 0.0);
            }
            // The cells of slab j: D_{0|1} L_d into the DEL rows, D_{0|1} D_{2|3} L_d into the
            // Jacobian.
            let half = 2 * (C + 1);
            for k in 0..last {
                let corners = self.corners(state, k);
                integrator.cell_gradient(t, &corners, &mut self.gradient);
                for (corner, node) in [(0, k), (1, k + 1)] {
                    if node == 0 || node == last {
                        continue;
                    }
                    for v in 0..=C {
                        self.rhs[(node - 1) * block + v] += self.gradient[corner * (C + 1) + v];
                    }
                }
                if refresh {
                    integrator.cell_hessian(t, &corners, &mut self.hessian);
                    for a in 0..half {
                        let row_node = k + a / (C + 1);
                        if row_node == 0 || row_node == last {
                            continue;
                        }
                        for b in 0..half {
                            let col_node = k + b / (C + 1);
                            if col_node == 0 || col_node == last {
                                continue;
                            }
                            let value = self.hessian[a * half + b];
                            self.add(
                                (row_node - 1) * block + a % (C + 1),
                                (col_node - 1) * block + b % (C + 1),
                                value,
                            );
                        }
                    }
                }
            }
            for i in 1..last {
                let row = (i - 1) * block;
                for c in 0..C {
                    self.rhs[row + c] += state.momentum_u[i][c];
                }
                self.rhs[row + C] += state.momentum_x[i];
                // The constraint forces λ_m ∇_{q_i} g_m(q^j) of the nodes m whose window holds i.
                for m in i.saturating_sub(2).max(1)..(i + 3).min(last) {
                    let offset = i + 2 - m;
                    for v in 0..=C {
                        let d = self.old_gradients[m * width + offset * (C + 1) + v];
                        self.rhs[row + v] += multipliers[m] * d;
                        if refresh {
                            self.add(row + v, (m - 1) * block + C + 1, d);
                        }
                    }
                }
                // The constraint at the next level.
                self.rhs[row + C + 1] = integrator.constraint_gradient(
                    i,
                    &self.next_x,
                    &self.next_u,
                    &mut self.new_gradients[i * width..(i + 1) * width],
                );
                if refresh {
                    for offset in 0..WINDOW {
                        let Some(m) = (i + offset).checked_sub(2).filter(|&m| m >= 1 && m < last)
                        else {
                            continue;
                        };
                        for v in 0..=C {
                            let d = self.new_gradients[i * width + offset * (C + 1) + v];
                            self.add(row + C + 1, (m - 1) * block + v, d);
                        }
                    }
                }
            }
            if refresh {
                self.solver
                    .factor(&self.pattern, &self.values)
                    .map_err(|_| Error::SingularMatrix { step: level, t })?;
                self.factorizations += 1;
                refresh = false;
            }
            self.solver
                .solve_in_place(&mut self.rhs)
                .map_err(|_| self.failure(level, t))?;
            // Damped: no cell shrinks below half its width in one iteration (a far start, a
            // fast front, would otherwise throw the iterate across a fold).
            let mut theta = 1.0f64;
            let shift = |i: usize| {
                if i == 0 || i == last {
                    0.0
                } else {
                    self.rhs[(i - 1) * block + C]
                }
            };
            for k in 0..last {
                let (shrink, width) =
                    (shift(k + 1) - shift(k), self.next_x[k + 1] - self.next_x[k]);
                if shrink > 0.5 * width {
                    theta = theta.min(0.5 * width / shrink);
                }
            }
            let mut size = 0.0f64;
            for i in 1..last {
                let row = (i - 1) * block;
                for c in 0..C {
                    self.next_u[i][c] -= theta * self.rhs[row + c];
                }
                self.next_x[i] -= theta * self.rhs[row + C];
                multipliers[i] -= theta * self.rhs[row + C + 1];
                size = size
                    .max(self.next_u[i].amax())
                    .max(self.next_x[i].abs())
                    .max(multipliers[i].abs());
            }
            increment = self.rhs.amax();
            if !increment.is_finite() {
                return Err(self.failure(level, t));
            }
            if theta == 1.0 && increment <= options.tolerance * (1.0 + size) {
                converged = true;
                break;
            }
            if theta < 1.0 || increment > REFACTOR_CONTRACTION * last_increment {
                refresh = true;
            }
            last_increment = increment;
        }
        if !converged {
            if let Some(fold) = self.fold(level, t) {
                return Err(fold);
            }
            return Err(Error::NonConvergence {
                step: level,
                t,
                iterations: options.max_iterations,
                residual: increment,
            });
        }
        Ok(())
    }

    /// A fold of the current iterate as an error, if it has one.
    /// Cell k of the slab between level j (`state`) and the candidate level j + 1.
    fn corners(&self, state: &State<C>, k: usize) -> Corners<C> {
        Corners {
            u: [
                state.u[k],
                state.u[k + 1],
                self.next_u[k],
                self.next_u[k + 1],
            ],
            x: [
                state.x[k],
                state.x[k + 1],
                self.next_x[k],
                self.next_x[k + 1],
            ],
        }
    }

    fn fold(&self, level: usize, t: f64) -> Option<Error> {
        super::check_fold(level, t, &self.next_x).err()
    }

    /// A failed linear solve or a non-finite increment: a fold if the iterate has folded,
    /// otherwise a singular matrix.
    fn failure(&self, level: usize, t: f64) -> Error {
        self.fold(level, t)
            .unwrap_or(Error::SingularMatrix { step: level, t })
    }
}
