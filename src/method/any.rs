//! [`AnyMethod`]: a method of the registry on ℝᴺ as one value, chosen at run time.
//!
//! A method chosen by name ([`crate::MethodSpec`]) reaches the stepping loop either as its
//! own type ([`crate::MethodSpec::visit_vector`]) or as this enum
//! ([`crate::MethodSpec::vector_method`]). Each method's step is the same code either way
//! (one `match` per call picks it); what differs is what is compiled: with the enum the
//! stepping loop and every `solve` mode (adaptivity, reparametrised time, SEM, dense output)
//! are instantiated once per model instead of once per model and method. Its SVI,
//! The command line
//! and the Python package run their methods this way; a program that knows its method at
//! compile time uses the method's type directly.

use crate::dimension::Dimension;
use crate::error::{Error, StepFailure};
use crate::method::collocation::SpectralCollocation;
use crate::method::hamiltonian::{
    HamiltonianCollocation, HamiltonianGalerkin, ImplicitMidpoint, Partitioned,
};
use crate::method::multiscale::Multiscale;
use crate::method::reference::{ExplicitEuler, ImplicitEuler, RungeKutta4};
use crate::method::space::{State, TangentMap};
use crate::method::variational::composition::Composition;
use crate::method::variational::discrete_lagrangian::{
    AdjointSymplecticEuler, Midpoint, SymplecticEuler, Trapezoid,
};
use crate::method::variational::stormer_verlet::StormerVerlet;
use crate::method::variational::svi::Svi;
use crate::method::variational::variational_integrator::VariationalIntegrator;
use crate::method::{Method, MethodInfo, StepAdjoint, StepReport};
use crate::model::Lagrangian;
use nalgebra::allocator::Allocator;
use nalgebra::{DMatrix, DVector, DefaultAllocator, OVector};

/// Receives a method on ℝᴺ as its concrete type ([`AnyMethod::visit`],
/// [`crate::MethodSpec::visit_vector`]); N is fixed (`Const<N>`) or chosen at run time
/// ([`crate::dimension::Dyn`]).
pub trait VectorMethodVisitor<N: Dimension>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    /// What the visit returns.
    type Output;
    /// Use `method`.
    fn visit<M: Method<N> + Clone>(self, method: M) -> Self::Output;
}

/// The failure of a step handed a workspace that another method built (a misuse of
/// [`Method`], never a numerical failure).
const FOREIGN_WORKSPACE: StepFailure = StepFailure::Unsupported {
    option: "workspace",
    reason: "the workspace was built by another method",
};

/// The enum, its workspace and the delegation of [`Method`], from one list of variants.
macro_rules! any_method {
    ($($variant:ident($method:ty)),+ $(,)?) => {
        /// A method of the registry on ℝᴺ, whichever it is (see the module documentation).
        #[derive(Debug, Clone)]
        pub enum AnyMethod {
            $(
                #[doc = concat!("[`", stringify!($method), "`].")]
                $variant($method),
            )+
        }

        /// The workspace of an [`AnyMethod`]: its method's own (one per run, so its size
        /// is the largest variant's and nothing is boxed).
        #[allow(clippy::large_enum_variant)]
        pub enum AnyWorkspace<N: Dimension>
        where
            DefaultAllocator: Allocator<N> + Allocator<N, N>,
        {
            $(
                #[doc = concat!("The workspace of [`", stringify!($method), "`].")]
                $variant(<$method as Method<N>>::Workspace),
            )+
        }

        $(
            impl From<$method> for AnyMethod {
                fn from(method: $method) -> Self {
                    AnyMethod::$variant(method)
                }
            }
        )+

        impl AnyMethod {
            /// Hand the method to `visitor` as its own type.
            pub fn visit<V: VectorMethodVisitor<N>, N: Dimension>(self, visitor: V) -> V::Output
            where
                DefaultAllocator: Allocator<N> + Allocator<N, N>,
            {
                match self {
                    $(AnyMethod::$variant(method) => visitor.visit(method),)+
                }
            }
        }

        impl<N: Dimension> Method<N> for AnyMethod
        where
            DefaultAllocator: Allocator<N> + Allocator<N, N>,
        {
            type Workspace = AnyWorkspace<N>;

            // Both are answered at run time by the method inside (`verlet_fractions`,
            // `points`), so both are the always-correct values.
            const COMPOSES_VERLET: bool = true;
            const WITHOUT_POINTS: bool = false;

            fn info(&self) -> MethodInfo {
                match self {
                    $(AnyMethod::$variant(method) => Method::<N>::info(method),)+
                }
            }

            fn workspace<L: Lagrangian<N>>(
                &self,
                model: &L,
                h: f64,
            ) -> Result<AnyWorkspace<N>, Error> {
                Ok(match self {
                    $(AnyMethod::$variant(method) => {
                        AnyWorkspace::$variant(method.workspace(model, h)?)
                    })+
                })
            }

            fn step<L: Lagrangian<N>>(
                &self,
                model: &L,
                workspace: &mut AnyWorkspace<N>,
                t: f64,
                h: f64,
                state: &State<N>,
                increment: &mut State<N>,
            ) -> Result<StepReport, StepFailure> {
                match (self, workspace) {
                    $((AnyMethod::$variant(method), AnyWorkspace::$variant(workspace)) => {
                        method.step(model, workspace, t, h, state, increment)
                    })+
                    #[allow(unreachable_patterns)]
                    _ => Err(FOREIGN_WORKSPACE),
                }
            }

            fn restart(&self, workspace: &mut AnyWorkspace<N>) {
                match (self, workspace) {
                    $((AnyMethod::$variant(method), AnyWorkspace::$variant(workspace)) => {
                        method.restart(workspace)
                    })+
                    #[allow(unreachable_patterns)]
                    _ => {}
                }
            }

            fn dense_output(
                &self,
                workspace: &AnyWorkspace<N>,
                state: &State<N>,
                h: f64,
                theta: f64,
            ) -> Option<(OVector<f64, N>, OVector<f64, N>)> {
                match (self, workspace) {
                    $((AnyMethod::$variant(method), AnyWorkspace::$variant(workspace)) => {
                        method.dense_output(workspace, state, h, theta)
                    })+
                    #[allow(unreachable_patterns)]
                    _ => None,
                }
            }

            fn velocity_into<L: Lagrangian<N>>(
                &self,
                model: &L,
                workspace: &AnyWorkspace<N>,
                t: f64,
                q: &OVector<f64, N>,
                p: &OVector<f64, N>,
                v: &mut OVector<f64, N>,
            ) -> Result<bool, Error> {
                match (self, workspace) {
                    $((AnyMethod::$variant(method), AnyWorkspace::$variant(workspace)) => {
                        method.velocity_into(model, workspace, t, q, p, v)
                    })+
                    #[allow(unreachable_patterns)]
                    _ => Ok(false),
                }
            }

            fn momentum_into(
                &self,
                workspace: &AnyWorkspace<N>,
                v: &OVector<f64, N>,
                p: &mut OVector<f64, N>,
            ) -> bool {
                match (self, workspace) {
                    $((AnyMethod::$variant(method), AnyWorkspace::$variant(workspace)) => {
                        method.momentum_into(workspace, v, p)
                    })+
                    #[allow(unreachable_patterns)]
                    _ => false,
                }
            }

            fn verlet_fractions(&self) -> Option<&[f64]> {
                match self {
                    $(AnyMethod::$variant(method) => Method::<N>::verlet_fractions(method),)+
                }
            }

            fn points(&self) -> Option<usize> {
                match self {
                    $(AnyMethod::$variant(method) => Method::<N>::points(method),)+
                }
            }

            fn keeps_sparsity<L: Lagrangian<N>>(&self, model: &L) -> bool {
                match self {
                    $(AnyMethod::$variant(method) => Method::<N>::keeps_sparsity(method, model),)+
                }
            }

            fn with_points(&self, points: usize) -> Option<Self> {
                match self {
                    $(AnyMethod::$variant(method) => {
                        Method::<N>::with_points(method, points).map(AnyMethod::$variant)
                    })+
                }
            }

            fn node_offsets<'a>(&self, workspace: &'a mut AnyWorkspace<N>) -> Option<&'a [f64]> {
                match (self, workspace) {
                    $((AnyMethod::$variant(method), AnyWorkspace::$variant(workspace)) => {
                        method.node_offsets(workspace)
                    })+
                    #[allow(unreachable_patterns)]
                    _ => None,
                }
            }

            fn discrete_energy<L: Lagrangian<N>>(
                &self,
                model: &L,
                workspace: &mut AnyWorkspace<N>,
                t: f64,
                h: f64,
                state: &State<N>,
            ) -> Option<f64> {
                match (self, workspace) {
                    $((AnyMethod::$variant(method), AnyWorkspace::$variant(workspace)) => {
                        method.discrete_energy(model, workspace, t, h, state)
                    })+
                    #[allow(unreachable_patterns)]
                    _ => None,
                }
            }

            fn tangent_map<L: Lagrangian<N>>(
                &self,
                model: &L,
                workspace: &mut AnyWorkspace<N>,
                t: f64,
                h: f64,
                state: &State<N>,
            ) -> Result<(State<N>, TangentMap<N>, StepReport), StepFailure> {
                match (self, workspace) {
                    $((AnyMethod::$variant(method), AnyWorkspace::$variant(workspace)) => {
                        method.tangent_map(model, workspace, t, h, state)
                    })+
                    #[allow(unreachable_patterns)]
                    _ => Err(FOREIGN_WORKSPACE),
                }
            }

            fn adjoint_step<L: Lagrangian<N>>(
                &self,
                model: &L,
                workspace: &mut AnyWorkspace<N>,
                t: f64,
                h: f64,
                state: &State<N>,
                increment: &mut State<N>,
                adjoint: &mut StepAdjoint<N>,
            ) -> Result<StepReport, StepFailure> {
                match (self, workspace) {
                    $((AnyMethod::$variant(method), AnyWorkspace::$variant(workspace)) => {
                        method.adjoint_step(model, workspace, t, h, state, increment, adjoint)
                    })+
                    #[allow(unreachable_patterns)]
                    _ => Err(FOREIGN_WORKSPACE),
                }
            }

            fn adjoint_apply(
                &self,
                workspace: &mut AnyWorkspace<N>,
                adjoint: &StepAdjoint<N>,
                lambda: &mut DVector<f64>,
                scratch: &mut DVector<f64>,
            ) -> Result<(), StepFailure> {
                match (self, workspace) {
                    $((AnyMethod::$variant(method), AnyWorkspace::$variant(workspace)) => {
                        method.adjoint_apply(workspace, adjoint, lambda, scratch)
                    })+
                    #[allow(unreachable_patterns)]
                    _ => Err(FOREIGN_WORKSPACE),
                }
            }

            fn tangent_apply(
                &self,
                workspace: &mut AnyWorkspace<N>,
                adjoint: &StepAdjoint<N>,
                columns: &mut DMatrix<f64>,
                scratch: &mut DMatrix<f64>,
            ) -> Result<(), StepFailure> {
                match (self, workspace) {
                    $((AnyMethod::$variant(method), AnyWorkspace::$variant(workspace)) => {
                        method.tangent_apply(workspace, adjoint, columns, scratch)
                    })+
                    #[allow(unreachable_patterns)]
                    _ => Err(FOREIGN_WORKSPACE),
                }
            }
        }
    };
}

any_method!(
    Svi(Svi),
    HamiltonianGalerkin(HamiltonianGalerkin),
    HamiltonianCollocation(HamiltonianCollocation),
    SpectralCollocation(SpectralCollocation),
    SymplecticEuler(VariationalIntegrator<SymplecticEuler>),
    AdjointSymplecticEuler(VariationalIntegrator<AdjointSymplecticEuler>),
    Midpoint(VariationalIntegrator<Midpoint>),
    Trapezoid(VariationalIntegrator<Trapezoid>),
    StormerVerlet(StormerVerlet),
    Composition(Composition),
    Partitioned(Partitioned),
    ImplicitMidpoint(ImplicitMidpoint),
    HamiltonianComposition(Composition<Partitioned>),
    Multiscale(Multiscale),
    ExplicitEuler(ExplicitEuler),
    ImplicitEuler(ImplicitEuler),
    RungeKutta4(RungeKutta4),
);

#[cfg(test)]
mod tests {
    use super::*;
    use crate::method::Euclidean;
    use crate::method::step::Step;
    use crate::test_models::Oscillator;
    use nalgebra::{U1, Vector1};

    /// A workspace of one method handed to another is a typed failure, not a panic.
    #[test]
    fn a_foreign_workspace_is_a_typed_failure() {
        let model = Oscillator::<true>;
        let svi = AnyMethod::from(Svi::new(4));
        let verlet = AnyMethod::from(StormerVerlet::default());
        let mut workspace = Method::<U1>::workspace(&verlet, &model, 0.1).unwrap();
        let state = State {
            q: Vector1::new(1.0),
            y: Vector1::new(0.0),
        };
        let mut increment = state;
        let failure = Step::<_, Euclidean<U1>>::step(
            &svi,
            &model,
            &mut workspace,
            0.0,
            0.1,
            &state,
            &mut increment,
        )
        .unwrap_err();
        assert_eq!(failure, FOREIGN_WORKSPACE);
    }
}
