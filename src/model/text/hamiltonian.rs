//! [`TextHamiltonian`]: a [`TextModel`] written as H(t, q, p) behind [`Hamiltonian<N>`] and
//! the H-side companions, its declarations constants of the type. It runs as
//! [`Canonical`](crate::model::hamiltonian::Canonical)`<TextHamiltonian<N, …>>`, so every
//! method of svi integrates it; the expressions, names and tapes are a text Lagrangian's, with
//! the momenta read where L reads the velocities.

use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, OVector, U1};

use super::TextModel;
use super::error::TextError;
use crate::dimension::{Dimension, dimension_of};
use crate::error::Error;
use crate::model::hamiltonian::{
    Hamiltonian, HamiltonianDefaults, HamiltonianExactSolution, HamiltonianInvariants,
    HamiltonianStructure, HamiltonianSymmetries,
};
use crate::scalar::Scalar;

/// A [`TextModel`] written as a Hamiltonian ([`TextSpec::hamiltonian`](super::TextSpec)) as a
/// [`Hamiltonian<N>`] (with [`HamiltonianSymmetries`], [`HamiltonianInvariants`] — none —,
/// [`HamiltonianExactSolution`] — none — and [`HamiltonianDefaults`]), of any number of
/// coordinates: `N` is [`crate::dimension::Dyn`] (what the command line uses) or a fixed
/// `Const<N>` equal to the model's size.
///
/// The other parameters are the model's declarations ([`Hamiltonian::TIME_DEPENDENT`],
/// [`Hamiltonian::FORCED`], and `QUADRATIC_KINETIC` for
/// [`HamiltonianStructure::QuadraticKinetic`]): constants of the type, as for
/// [`TextLagrangian`](super::TextLagrangian). The defaults (time-dependent, forced, general)
/// fit every model; [`TextHamiltonian::new`] rejects declarations the model does not allow.
///
/// ```
/// use nalgebra::DVector;
/// use svi::model::text::{TextHamiltonian, TextModel, TextSpec};
/// use svi::{Canonical, Dyn, Initial, Integrator, Svi};
///
/// let spec = TextSpec {
///     hamiltonian: "0.5*(px^2 + py^2) - mu/sqrt(x^2 + y^2)".into(),
///     coordinates: vec!["x".into(), "y".into()],
///     parameters: vec![("mu".into(), 1.0)],
///     ..TextSpec::default()
/// };
/// // Autonomous, unforced, ½pᵀAp + V(q) with A constant: all three may be declared.
/// let kepler = TextHamiltonian::<Dyn, false, false, true>::new(TextModel::new(&spec)?)?;
/// let integrator = Integrator::new(Canonical::new(kepler), Svi::new(6));
/// let initial = Initial::Momentum {
///     q: DVector::from_vec(vec![1.0, 0.0]),
///     p: DVector::from_vec(vec![0.0, 1.0]),
/// };
/// let run = integrator.run(0.0, initial, 0.1, 6.0, &mut ()).unwrap();
/// let exact = DVector::from_vec(vec![6f64.cos(), 6f64.sin()]);
/// assert!((run.last.q - exact).amax() < 1e-10);
/// # Ok::<(), svi::model::text::TextError>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct TextHamiltonian<
    N,
    const TIME_DEPENDENT: bool = true,
    const FORCED: bool = true,
    const QUADRATIC_KINETIC: bool = false,
> {
    model: TextModel,
    dimension: std::marker::PhantomData<N>,
}

impl<N: Dimension, const TIME_DEPENDENT: bool, const FORCED: bool, const QUADRATIC_KINETIC: bool>
    TextHamiltonian<N, TIME_DEPENDENT, FORCED, QUADRATIC_KINETIC>
where
    DefaultAllocator: Allocator<N>,
{
    /// `model` as a Hamiltonian on T*ℝᴺ with the type's declarations.
    ///
    /// # Errors
    /// [`TextError::Declaration`] for a model written as a Lagrangian, if `N` is fixed to
    /// another size than the model's, or a declaration does not hold: `TIME_DEPENDENT =
    /// false` with `t` in H, `FORCED = false` with forces, `QUADRATIC_KINETIC = true` for H
    /// not recognised as ½pᵀAp + V(t, q).
    pub fn new(model: TextModel) -> Result<Self, TextError> {
        let declaration = |reason: String| {
            Err(TextError::Declaration {
                holder: "TextHamiltonian",
                reason,
            })
        };
        if !model.is_hamiltonian() {
            return declaration(
                "the model is written as a Lagrangian: TextLagrangian holds it".into(),
            );
        }
        if let Err(reason) = dimension_of::<N>(model.dimension()) {
            return declaration(reason);
        }
        if model.time_dependent() && !TIME_DEPENDENT {
            return declaration("H depends on t, but TIME_DEPENDENT = false".into());
        }
        if model.forced() && !FORCED {
            return declaration("the model has forces, but FORCED = false".into());
        }
        if QUADRATIC_KINETIC
            && model.hamiltonian_structure() != HamiltonianStructure::QuadraticKinetic
        {
            return declaration(
                "QUADRATIC_KINETIC = true, but H is not recognised as ½pᵀAp + V(t, q)".into(),
            );
        }
        Ok(TextHamiltonian {
            model,
            dimension: std::marker::PhantomData,
        })
    }

    /// The model.
    pub fn model(&self) -> &TextModel {
        &self.model
    }
}

impl<N: Dimension, const TIME_DEPENDENT: bool, const FORCED: bool, const QUADRATIC_KINETIC: bool>
    Hamiltonian<N> for TextHamiltonian<N, TIME_DEPENDENT, FORCED, QUADRATIC_KINETIC>
where
    DefaultAllocator: Allocator<N>,
{
    const TIME_DEPENDENT: bool = TIME_DEPENDENT;
    const FORCED: bool = FORCED;
    const STRUCTURE: HamiltonianStructure = if QUADRATIC_KINETIC {
        HamiltonianStructure::QuadraticKinetic
    } else {
        HamiltonianStructure::General
    };

    fn dimension(&self) -> usize {
        self.model.dimension()
    }

    /// The declared structure, or [`HamiltonianStructure::Separable`] when the text is
    /// T(p) + V(t, q) ([`TextModel::hamiltonian_structure`]).
    fn structure(&self) -> HamiltonianStructure {
        match (QUADRATIC_KINETIC, self.model.hamiltonian_structure()) {
            (true, _) => HamiltonianStructure::QuadraticKinetic,
            (false, HamiltonianStructure::Separable) => HamiltonianStructure::Separable,
            (false, _) => HamiltonianStructure::General,
        }
    }

    #[inline]
    fn hamiltonian<D: Scalar>(&self, t: D, q: &OVector<D, N>, p: &OVector<D, N>) -> D {
        let tapes = &self.model.tapes;
        if QUADRATIC_KINETIC && let Some(split) = &tapes.constant_mass {
            // ½pᵀAp without a tape, plus V(t, q).
            return split.evaluate(t, q.as_slice(), p.as_slice());
        }
        tapes.lagrangian.evaluate(t, q.as_slice(), p.as_slice())
    }

    #[inline]
    fn external_force<D: Scalar>(
        &self,
        t: D,
        q: &OVector<D, N>,
        p: &OVector<D, N>,
    ) -> OVector<D, N> {
        let forces = &self.model.tapes.forces;
        let (n, _) = q.shape_generic();
        if forces.is_empty() {
            return OVector::zeros_generic(n, U1);
        }
        OVector::from_fn_generic(n, U1, |i, _| {
            forces[i].evaluate(t, q.as_slice(), p.as_slice())
        })
    }
}

impl<N: Dimension, const TIME_DEPENDENT: bool, const FORCED: bool, const QUADRATIC_KINETIC: bool>
    HamiltonianSymmetries<N> for TextHamiltonian<N, TIME_DEPENDENT, FORCED, QUADRATIC_KINETIC>
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

impl<N: Dimension, const TIME_DEPENDENT: bool, const FORCED: bool, const QUADRATIC_KINETIC: bool>
    HamiltonianInvariants<N> for TextHamiltonian<N, TIME_DEPENDENT, FORCED, QUADRATIC_KINETIC>
where
    DefaultAllocator: Allocator<N>,
{
}

impl<N: Dimension, const TIME_DEPENDENT: bool, const FORCED: bool, const QUADRATIC_KINETIC: bool>
    HamiltonianExactSolution<N> for TextHamiltonian<N, TIME_DEPENDENT, FORCED, QUADRATIC_KINETIC>
where
    DefaultAllocator: Allocator<N>,
{
    /// None: a text model has no closed-form solution.
    fn exact_solution(
        &self,
        _t0: f64,
        _q0: &OVector<f64, N>,
        _p0: &OVector<f64, N>,
        _t: f64,
    ) -> Option<(OVector<f64, N>, OVector<f64, N>)> {
        None
    }
}

impl<N: Dimension, const TIME_DEPENDENT: bool, const FORCED: bool, const QUADRATIC_KINETIC: bool>
    HamiltonianDefaults<N> for TextHamiltonian<N, TIME_DEPENDENT, FORCED, QUADRATIC_KINETIC>
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
    use crate::dimension::Dyn;
    use crate::model::hamiltonian::Canonical;
    use crate::model::text::{TextLagrangian, TextSpec};
    use crate::model::{Lagrangian, Structure};
    use nalgebra::{DVector, SVector, U2};

    fn spec(hamiltonian: &str) -> TextSpec {
        TextSpec {
            hamiltonian: hamiltonian.into(),
            coordinates: vec!["x".into(), "y".into()],
            parameters: vec![("B".into(), 2.0)],
            ..TextSpec::default()
        }
    }

    /// The structure read off H: ½pᵀAp + V with constant A is quadratic kinetic (A from
    /// parameters and numbers), a coupling of p and q or a varying coefficient is general;
    /// the declarations are checked against it.
    #[test]
    fn declarations_follow_the_text_of_h() {
        let quadratic = TextModel::new(&spec("(px^2 + 3*py^2)/(2*B) - 1/sqrt(x^2 + y^2)")).unwrap();
        assert!(quadratic.is_hamiltonian());
        assert_eq!(
            quadratic.hamiltonian_structure(),
            HamiltonianStructure::QuadraticKinetic
        );
        // The Lagrangian side's declaration is not H's.
        assert_eq!(quadratic.structure(), Structure::General);
        assert!(TextHamiltonian::<U2, false, false, true>::new(quadratic.clone()).is_ok());
        assert!(TextLagrangian::<Dyn>::new(quadratic).is_err());
        // T(p) + V(t, q) with any T: separable (constant factors and sums of such parts).
        for separable in [
            "sqrt(1 + px^2 + py^2)",
            "B*(sqrt(1 + px^2) + sqrt(1 + py^2)) + (x^2 + y^2)/2 - x*cos(t)",
            "2*cosh(px)/B - x*y + py^4",
        ] {
            let model = TextModel::new(&spec(separable)).unwrap();
            assert_eq!(
                model.hamiltonian_structure(),
                HamiltonianStructure::Separable,
                "{separable}"
            );
            assert!(TextHamiltonian::<Dyn, false, false, true>::new(model.clone()).is_err());
            let h = TextHamiltonian::<Dyn>::new(model).unwrap();
            assert_eq!(
                Hamiltonian::<Dyn>::structure(&h),
                HamiltonianStructure::Separable
            );
        }
        for general in [
            "((px + B*y/2)^2 + (py - B*x/2)^2)/2",
            "(1 + x^2)*px^2/2 + py^2/2",
            "x*px + py^2",
            "sqrt(1 + px^2)*(1 + y^2)",
        ] {
            let model = TextModel::new(&spec(general)).unwrap();
            assert_eq!(
                model.hamiltonian_structure(),
                HamiltonianStructure::General,
                "{general}"
            );
            assert!(TextHamiltonian::<Dyn, false, false, true>::new(model.clone()).is_err());
            assert!(TextHamiltonian::<Dyn, false, false, false>::new(model).is_ok());
        }
        let general = TextHamiltonian::<Dyn>::new(TextModel::new(&spec("x*px + py^2")).unwrap());
        assert_eq!(
            Hamiltonian::<Dyn>::structure(&general.unwrap()),
            HamiltonianStructure::General
        );
        let mut driven = spec("(px^2 + py^2)/2 - x*cos(t)");
        driven.forces = vec!["-0.1*px".into(), "-0.1*py".into()];
        let model = TextModel::new(&driven).unwrap();
        assert!(model.time_dependent() && model.forced());
        assert!(TextHamiltonian::<Dyn, false, true>::new(model.clone()).is_err());
        assert!(TextHamiltonian::<Dyn, true, false>::new(model.clone()).is_err());
        let driven = TextHamiltonian::<U2>::new(model).unwrap();
        let (q, p) = (SVector::from([0.5, 0.0]), SVector::from([2.0, -1.0]));
        assert_eq!(driven.hamiltonian(0.0, &q, &p), 2.5 - 0.5);
        assert_eq!(driven.external_force(0.0, &q, &p).as_slice(), &[-0.2, 0.1]);
    }

    /// H and the Lagrangian of `Canonical` at a point, by hand: for the uniform magnetic field,
    /// L = |q̇|²/2 + q̇·A(q) with A = B(−y, x)/2, and p = q̇ + A.
    #[test]
    fn a_text_hamiltonian_is_a_model_through_canonical() {
        let model = TextModel::new(&spec("((px + B*y/2)^2 + (py - B*x/2)^2)/2")).unwrap();
        let model =
            Canonical::new(TextHamiltonian::<Dyn, false, false, false>::new(model).unwrap());
        let q = DVector::from_vec(vec![0.3, -0.7]);
        let v = DVector::from_vec(vec![1.1, 0.4]);
        let (b, x, y) = (2.0, 0.3, -0.7);
        let expected =
            0.5 * (1.1f64.powi(2) + 0.4f64.powi(2)) + 1.1 * (-b * y / 2.0) + 0.4 * (b * x / 2.0);
        assert!((model.lagrangian(0.0, &q, &v) - expected).abs() < 1e-14);
        assert_eq!(Lagrangian::dimension(&model), 2);
    }

    #[test]
    fn misuses_of_a_text_hamiltonian_are_named() {
        let error = |spec: &TextSpec| TextModel::new(spec).unwrap_err().to_string();
        assert_eq!(
            error(&spec("(vx^2 + py^2)/2")),
            "'vx' at column 2 of hamiltonian is a velocity, but a Hamiltonian is a function of \
             the momenta: write px"
        );
        assert!(error(&spec("(px^2 + pz^2)/2")).starts_with(
            "unknown symbol 'pz' at column 9 of hamiltonian (known: x, y, px, py, t, B)"
        ));
        let both = TextSpec {
            lagrangian: "vx^2/2".into(),
            ..spec("px^2/2")
        };
        assert_eq!(
            TextModel::new(&both),
            Err(TextError::LagrangianAndHamiltonian)
        );
        let constrained = TextSpec {
            constraints: vec!["x^2 + y^2 - 1".into()],
            ..spec("(px^2 + py^2)/2")
        };
        assert!(error(&constrained).starts_with("constraints is not supported here"));
        // A coordinate whose momentum would be another name.
        let clash = TextSpec {
            coordinates: vec!["x".into(), "px".into()],
            ..spec("x")
        };
        assert!(error(&clash).contains("its momentum 'px' is also a coordinate"));
        let chain = TextSpec {
            coordinates: vec!["q[1..n]".into()],
            ..spec("x")
        };
        assert!(crate::model::text::TextChainModel::new(&chain).is_err());
    }

    /// A relativistic H written as text is read as separable: `verlet-h` and its compositions
    /// step it explicitly (no Newton iteration), and kahan-li8-h meets svi-h on it.
    #[test]
    fn a_separable_text_hamiltonian_steps_explicitly() {
        use crate::method::Initial;
        use crate::method::registry::MethodSpec;
        use crate::stepping::run::Integrator;
        let relativistic = TextModel::new(&spec(
            "sqrt(1 + px^2) + sqrt(1 + py^2) + B*(x^2 + y^2)/2 - x*y",
        ))
        .unwrap();
        let model =
            Canonical::new(TextHamiltonian::<Dyn, false, false, false>::new(relativistic).unwrap());
        let initial = Initial::Momentum {
            q: DVector::from_vec(vec![1.0, 0.0]),
            p: DVector::from_vec(vec![0.0, 2.0]),
        };
        let run = |name: &str, h: f64| {
            let method = name.parse::<MethodSpec>().unwrap().vector_method().unwrap();
            Integrator::new(model.clone(), method)
                .run(0.0, initial.clone(), h, 5.0, &mut ())
                .unwrap()
        };
        let explicit = run("kahan-li8-h", 0.05);
        assert_eq!(explicit.statistics.iterations, 0);
        assert_eq!(run("verlet-h", 0.05).statistics.iterations, 0);
        let reference = run("svi-h:8", 0.05);
        let gap = (&explicit.last.q - &reference.last.q).amax();
        assert!(gap < 1e-9, "{gap:e}");
    }
}
