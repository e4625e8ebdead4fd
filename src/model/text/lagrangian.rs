//! [`TextLagrangian`]: a [`TextModel`] behind [`Lagrangian<N>`] and the other traits of a
//! model, its declarations constants of the type, and the force of a constant-mass L run by
//! its compiled program on many points at once ([`Lagrangian::batch_force`]).

use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, OVector, U1};

use super::TextModel;
use super::batch::{MAX_REGISTERS, Program, Source};
use super::error::TextError;
use crate::dimension::{Dimension, dimension_of};
use crate::error::Error;
use crate::model::{Defaults, ExactSolution, Invariants, Lagrangian, Structure, Symmetries};
use crate::scalar::Scalar;

/// A [`TextModel`] as a [`Lagrangian<N>`] (with [`Symmetries`], [`Invariants`] — none —,
/// [`ExactSolution`] — none — and [`Defaults`]), of any number of coordinates: `N` is
/// [`crate::dimension::Dyn`] (the size is the model's, chosen at run time; what the command
/// line uses) or a fixed `Const<N>` equal to the model's size.
///
/// The other parameters are the model's declarations ([`Lagrangian::TIME_DEPENDENT`],
/// [`Lagrangian::FORCED`], and `CONSTANT_MASS` for [`Structure::ConstantMass`]): constants
/// of the type, so a caller that learns the model's at run time dispatches on them. The
/// defaults (time-dependent, forced, general) fit every model; [`TextLagrangian::new`]
/// rejects declarations the model does not allow.
#[derive(Debug, Clone, PartialEq)]
pub struct TextLagrangian<
    N,
    const TIME_DEPENDENT: bool = true,
    const FORCED: bool = true,
    const CONSTANT_MASS: bool = false,
> {
    model: TextModel,
    dimension: std::marker::PhantomData<N>,
}

impl<N: Dimension, const TIME_DEPENDENT: bool, const FORCED: bool, const CONSTANT_MASS: bool>
    TextLagrangian<N, TIME_DEPENDENT, FORCED, CONSTANT_MASS>
where
    DefaultAllocator: Allocator<N>,
{
    /// `model` as a Lagrangian on ℝᴺ with the type's declarations.
    ///
    /// # Errors
    /// [`TextError::Declaration`] for a model written as a Hamiltonian, if `N` is fixed to
    /// another size than the model's, or a declaration does
    /// not hold: `TIME_DEPENDENT = false` with `t` in L, `FORCED = false` with forces,
    /// `CONSTANT_MASS = true` for L not recognised as constant-mass.
    pub fn new(model: TextModel) -> Result<Self, TextError> {
        let declaration = |reason: String| {
            Err(TextError::Declaration {
                holder: "TextLagrangian",
                reason,
            })
        };
        if model.is_hamiltonian() {
            return declaration(
                "the model is written as a Hamiltonian: TextHamiltonian holds it".into(),
            );
        }
        if let Err(reason) = dimension_of::<N>(model.dimension()) {
            return declaration(reason);
        }
        if model.time_dependent() && !TIME_DEPENDENT {
            return declaration("L depends on t, but TIME_DEPENDENT = false".into());
        }
        if model.forced() && !FORCED {
            return declaration("the model has forces, but FORCED = false".into());
        }
        if CONSTANT_MASS && model.structure() != Structure::ConstantMass {
            return declaration(
                "CONSTANT_MASS = true, but L is not recognised as ½q̇ᵀMq̇ − V(t, q)".into(),
            );
        }
        Ok(TextLagrangian {
            model,
            dimension: std::marker::PhantomData,
        })
    }

    /// The model.
    pub fn model(&self) -> &TextModel {
        &self.model
    }
}

impl<N: Dimension, const TIME_DEPENDENT: bool, const FORCED: bool, const CONSTANT_MASS: bool>
    Lagrangian<N> for TextLagrangian<N, TIME_DEPENDENT, FORCED, CONSTANT_MASS>
where
    DefaultAllocator: Allocator<N>,
{
    const TIME_DEPENDENT: bool = TIME_DEPENDENT;
    const FORCED: bool = FORCED;
    const STRUCTURE: Structure = if CONSTANT_MASS {
        Structure::ConstantMass
    } else {
        Structure::General
    };

    fn dimension(&self) -> usize {
        self.model.dimension()
    }

    #[inline]
    fn lagrangian<D: Scalar>(&self, t: D, q: &OVector<D, N>, v: &OVector<D, N>) -> D {
        let tapes = &self.model.tapes;
        if CONSTANT_MASS && let Some(split) = &tapes.constant_mass {
            // ½q̇ᵀMq̇ without a tape, plus U(t, q).
            return split.evaluate(t, q.as_slice(), v.as_slice());
        }
        tapes.lagrangian.evaluate(t, q.as_slice(), v.as_slice())
    }

    #[inline]
    fn external_force<D: Scalar>(
        &self,
        t: D,
        q: &OVector<D, N>,
        v: &OVector<D, N>,
    ) -> OVector<D, N> {
        let forces = &self.model.tapes.forces;
        let (n, _) = q.shape_generic();
        if forces.is_empty() {
            return OVector::zeros_generic(n, U1);
        }
        OVector::from_fn_generic(n, U1, |i, _| {
            forces[i].evaluate(t, q.as_slice(), v.as_slice())
        })
    }

    /// A constant-mass L: the compiled program of ∂U/∂q on up to `BATCH_LANES` points at once.
    #[inline]
    fn batch_force(
        &self,
        times: &[f64],
        positions: &[OVector<f64, N>],
        _v: &OVector<f64, N>,
        forces: &mut [OVector<f64, N>],
    ) -> bool {
        let program = match &self.model.tapes.force {
            Some(program) if CONSTANT_MASS => program,
            _ => return false,
        };
        // Registers no wider than the points need: SVI 7/6's 6 Gauss points fill 6 lanes,
        // the default 6/12's 12 (even widths: whole vector instructions).
        let arguments = (program, times, positions, forces);
        match positions.len() {
            0..=4 => batch_force_in::<4, N>(arguments),
            5..=6 => batch_force_in::<6, N>(arguments),
            7..=8 => batch_force_in::<8, N>(arguments),
            9..=12 => batch_force_in::<12, N>(arguments),
            _ => batch_force_in::<BATCH_LANES, N>(arguments),
        }
        true
    }
}

/// The arguments of [`batch_force_in`]: the program, the times, positions and forces.
type BatchForce<'a, N> = (
    &'a Program,
    &'a [f64],
    &'a [OVector<f64, N>],
    &'a mut [OVector<f64, N>],
);

/// ∂U/∂q at the points by `program`, `W` points at once, in the smallest register file
/// that holds the program (it is zeroed at every call).
#[inline]
fn batch_force_in<const W: usize, N: Dimension>(
    (program, times, positions, forces): BatchForce<'_, N>,
) where
    DefaultAllocator: Allocator<N>,
{
    if program.register_count() <= 8 {
        batch_force_with(program, &mut [[0.0; W]; 8], times, positions, forces);
    } else {
        let registers = &mut [[0.0; W]; MAX_REGISTERS];
        batch_force_with(program, registers, times, positions, forces);
    }
}

/// ∂U/∂q at the points by `program`, `W` points at once, with `registers`.
#[inline]
fn batch_force_with<const W: usize, N: Dimension>(
    program: &Program,
    registers: &mut [[f64; W]],
    times: &[f64],
    positions: &[OVector<f64, N>],
    forces: &mut [OVector<f64, N>],
) where
    DefaultAllocator: Allocator<N>,
{
    for ((times, positions), forces) in times
        .chunks(W)
        .zip(positions.chunks(W))
        .zip(forces.chunks_mut(W))
    {
        program.forces(
            registers,
            positions.len(),
            |source, lanes| match source {
                Source::Time => lanes[..times.len()].copy_from_slice(times),
                Source::Coordinate(u) => {
                    for (x, q) in lanes.iter_mut().zip(positions) {
                        *x = q[u];
                    }
                }
                // U(t, q) reads no velocity.
                Source::Velocity(_) => lanes.fill(0.0),
            },
            |u, lane, value| forces[lane].as_mut_slice()[u] = value,
        );
    }
}

/// The most points a text model's force program runs at once ([`Lagrangian::batch_force`]):
/// as many as SVI's usual quadrature rules have.
const BATCH_LANES: usize = 16;

impl<N: Dimension, const TIME_DEPENDENT: bool, const FORCED: bool, const CONSTANT_MASS: bool>
    Symmetries<N> for TextLagrangian<N, TIME_DEPENDENT, FORCED, CONSTANT_MASS>
where
    DefaultAllocator: Allocator<N>,
{
    fn generator_count(&self) -> usize {
        self.model.generators.len()
    }

    /// `J1`, `J2`, ... in the order of [`TextSpec::symmetries`](super::TextSpec::symmetries).
    ///
    /// # Panics
    /// If `index >= generator_count()`.
    fn momentum_name(&self, index: usize) -> &'static str {
        self.model.momentum_names[index]
    }

    /// # Panics
    /// If `index >= generator_count()`.
    fn generator(&self, index: usize, q: &OVector<f64, N>) -> OVector<f64, N> {
        self.model.generator(index, q)
    }
}

impl<N: Dimension, const TIME_DEPENDENT: bool, const FORCED: bool, const CONSTANT_MASS: bool>
    Invariants<N> for TextLagrangian<N, TIME_DEPENDENT, FORCED, CONSTANT_MASS>
where
    DefaultAllocator: Allocator<N>,
{
}

impl<N: Dimension, const TIME_DEPENDENT: bool, const FORCED: bool, const CONSTANT_MASS: bool>
    ExactSolution<N> for TextLagrangian<N, TIME_DEPENDENT, FORCED, CONSTANT_MASS>
where
    DefaultAllocator: Allocator<N>,
{
    /// None: a text model has no closed-form solution.
    fn exact_solution(
        &self,
        _t0: f64,
        _q0: &OVector<f64, N>,
        _v0: &OVector<f64, N>,
        _t: f64,
    ) -> Option<(OVector<f64, N>, OVector<f64, N>)> {
        None
    }
}

impl<N: Dimension, const TIME_DEPENDENT: bool, const FORCED: bool, const CONSTANT_MASS: bool>
    Defaults<N> for TextLagrangian<N, TIME_DEPENDENT, FORCED, CONSTANT_MASS>
where
    DefaultAllocator: Allocator<N>,
{
    /// [`TextModel::NAME`].
    fn name(&self) -> &'static str {
        TextModel::NAME
    }

    fn coordinate_names(&self) -> Vec<String> {
        self.model
            .coordinate_names()
            .iter()
            .map(|name| name.to_string())
            .collect()
    }

    fn parameters(&self) -> Vec<(&'static str, f64)> {
        self.model.parameters()
    }

    fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), Error> {
        self.model.set_parameter(name, value)
    }

    /// [`TextModel::rest_state`].
    fn initial_state(&self) -> (f64, OVector<f64, N>, OVector<f64, N>) {
        self.model.rest_state()
    }

    /// [`TextModel::DEFAULT_STEP`].
    fn default_step(&self) -> f64 {
        TextModel::DEFAULT_STEP
    }

    /// [`TextModel::DEFAULT_HORIZON`].
    fn default_horizon(&self) -> f64 {
        TextModel::DEFAULT_HORIZON
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::derived::LagrangianExt;
    use crate::model::text::tests::spec;
    use nalgebra::DVector;

    /// The compiled force program with the points as lanes is the force of the dual
    /// numbers, point by point, for a time-dependent constant-mass L, at every register
    /// width (3, 6, 7 and 12 points; more points than one batch holds).
    #[test]
    fn the_batched_force_is_the_force_point_by_point() {
        let text = spec(
            "0.5*(vx^2 + 3*vy^2) - x^2*cos(t) - sin(x*y) + 1/sqrt(1 + x^2 + y^4)",
            &["x", "y"],
        );
        let model = TextModel::new(&text).unwrap();
        let model = TextLagrangian::<crate::dimension::Dyn, true, false, true>::new(model).unwrap();
        let v = DVector::from_column_slice(&[0.3, -0.4]);
        let points = |count: usize| {
            let times: Vec<f64> = (0..count).map(|k| 0.1 * k as f64).collect();
            let positions: Vec<DVector<f64>> = (0..count)
                .map(|k| {
                    DVector::from_column_slice(&[(0.7 * k as f64).sin(), 0.2 * k as f64 - 1.0])
                })
                .collect();
            (times, positions)
        };
        for count in [3, 6, 7, 12, BATCH_LANES + 5] {
            let (times, positions) = points(count);
            let mut forces = vec![DVector::zeros(2); count];
            assert!(model.batch_force(&times, &positions, &v, &mut forces));
            for ((&t, q), force) in times.iter().zip(&positions).zip(&forces) {
                let mut expected = DVector::zeros(2);
                model.force_into(t, q, &v, &mut expected);
                assert!(
                    (force - &expected).amax() <= 1e-14 * expected.amax().max(1.0),
                    "{count} points: {force} {expected}"
                );
            }
        }
        let (times, positions) = points(6);
        let mut forces = vec![DVector::zeros(2); 6];
        // A general L offers no batch: the integrators take the points one by one.
        let general = spec("0.5*(1 + x^2)*vx^2 + 0.5*vy^2 - x^2", &["x", "y"]);
        let general = TextModel::new(&general).unwrap();
        let general = TextLagrangian::<crate::dimension::Dyn>::new(general).unwrap();
        assert!(!general.batch_force(&times, &positions, &v, &mut forces));
    }
}
