//! What a scene's run does differently on each space, ℝᴺ (fixed N, and runtime-sized ℝⁿ for
//! chains and lattices, [`Chain`]), SO(3) and the other Lie groups: the command line's side
//! of svi's [`Space`]. The one run path ([`crate::run`]) is written once over
//! [`RunSpace`]; everything particular to a space is here.

use nalgebra::allocator::Allocator;
use nalgebra::{DVector, DefaultAllocator, OVector, SVector};
use svi::lie_group::so3::orthogonality_error;
use svi::lie_group::{
    AngularMomentumError, DefectError, GroupDefaults, GroupInitial, GroupLagrangian,
    GroupLagrangianExt, GroupPoint, GroupSolutionError, GroupSpace, LieGroup, OrthogonalityError,
    RigidBodyDefaults, RigidBodyExt, RigidInitial, RigidPoint, SO3,
};
use svi::method::space::Space;
use svi::observer::{EnergyError, InvariantError, MomentumError, Observer, SolutionError};
use svi::{Defaults, Euclidean, Initial, LagrangianExt, PhasePoint};
use svi::{Dimension, Dyn};
use svi_models::{AnyChain, ChainView, GroupZooModel, RigidZooModel, ZooModel};

use crate::report::csv::{RIGID_CSV_HEADER, csv_header};
use crate::report::summary::{Conservation, StateSummary};
use crate::scene::Scene;
use crate::scene::schema::Diagnostic;

/// The parts of a run on the space `Self` with models `L` that differ between spaces: the
/// diagnostics observers, the summary fields and the trajectory CSV columns.
pub trait RunSpace<L>: Space {
    /// Whether summaries list `retries`, `adapt`, `tol`, `adaptivity` and `outputs` even for
    /// a plain fixed-step run (on ℝᴺ, whose summaries have always had them; on SO(3) they
    /// appear when the run uses them).
    const LISTS_RUN_FIELDS: bool;

    /// The observers of the diagnostics a scene may ask for (each an `Option`: `None` when
    /// not asked for or not measurable for the model).
    type Diagnostics: Observer<L, Self::Point>;

    /// The observers of the diagnostics `scene` asks for, and only those.
    fn diagnostics(model: &L, scene: &Scene) -> Self::Diagnostics;

    /// The largest energy error and the conservation fields of the summary, from the
    /// observers after the run (`last`: the final point).
    fn measured(
        model: &L,
        diagnostics: Self::Diagnostics,
        first: &Self::Point,
        last: &Self::Point,
    ) -> (Option<f64>, Conservation);

    /// The model's name.
    fn model_name(model: &L) -> &'static str;

    /// The model's parameters, in its order.
    fn parameters(model: &L) -> Vec<(&'static str, f64)>;

    /// The names of the configuration coordinates, where they have names (ℝᴺ).
    fn coordinates(model: &L) -> Option<Vec<String>>;

    /// The energy of a point.
    fn energy(model: &L, point: &Self::Point) -> f64;

    /// Whether the model conserves energy (autonomous and unforced): the health check's
    /// energy test applies.
    fn conserves_energy(model: &L) -> bool;

    /// The scale of the energy at a point, max(|E|, ½|p·q̇|), against which the health check
    /// measures energy errors.
    fn energy_scale(model: &L, point: &Self::Point) -> f64;

    /// The largest component of a point's configuration, where it can grow without bound
    /// (ℝᴺ; `None` on SO(3)).
    fn extent(point: &Self::Point) -> Option<f64>;

    /// A point as summary fields.
    fn state(point: &Self::Point) -> StateSummary;

    /// The Newton start of the inverse Legendre map at the initial state, for the summary's
    /// initial energy: the initial velocity or momentum on ℝᴺ, rest on SO(3).
    fn initial_guess_at_rest(initial: &Self::Initial) -> Self::Velocity;

    /// The number of configuration coordinates of the initial state (the progress bar's
    /// measure of work per step).
    fn coordinate_count(initial: &Self::Initial) -> usize;

    /// The header line of the trajectory CSV (with its newline).
    fn csv_header(model: &L) -> String;

    /// The numbers of one trajectory CSV row, appended to `row`.
    fn csv_row(model: &L, point: &Self::Point, row: &mut Vec<f64>);
}

impl<L: ZooModel<N>, N: Dimension> RunSpace<L> for Euclidean<N>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    const LISTS_RUN_FIELDS: bool = true;

    /// Energy, Noether momenta (for models with symmetries), error against the exact
    /// solution (`None` at the end where the model has none).
    type Diagnostics = (
        Option<EnergyError>,
        Option<MomentumError>,
        Option<SolutionError<N>>,
    );

    fn diagnostics(model: &L, scene: &Scene) -> Self::Diagnostics {
        (
            scene.wants(Diagnostic::Energy).then(EnergyError::default),
            (scene.wants(Diagnostic::Momentum) && model.generator_count() > 0)
                .then(MomentumError::default),
            scene
                .wants(Diagnostic::Solution)
                .then(SolutionError::<N>::default),
        )
    }

    fn measured(
        model: &L,
        (energy, momentum, solution): Self::Diagnostics,
        first: &PhasePoint<N>,
        last: &PhasePoint<N>,
    ) -> (Option<f64>, Conservation) {
        let exact = model.exact_solution(first.t, &first.q, &first.v, last.t);
        (
            energy.map(|e| e.max),
            Conservation::Vector {
                momentum_error_max: momentum.map(|m| m.max),
                solution_error_max: solution.and_then(|s| s.max),
                solution_error_final: exact.map(|(q, _)| (&last.q - q).norm()),
            },
        )
    }

    fn model_name(model: &L) -> &'static str {
        Defaults::name(model)
    }

    fn parameters(model: &L) -> Vec<(&'static str, f64)> {
        Defaults::parameters(model)
    }

    fn coordinates(model: &L) -> Option<Vec<String>> {
        Some(model.coordinate_names())
    }

    fn energy(model: &L, point: &PhasePoint<N>) -> f64 {
        model.phase_energy(point.t, &point.q, &point.v, &point.p)
    }

    fn conserves_energy(_: &L) -> bool {
        !L::FORCED && !L::TIME_DEPENDENT
    }

    fn energy_scale(model: &L, point: &PhasePoint<N>) -> f64 {
        let energy = <Self as RunSpace<L>>::energy(model, point).abs();
        energy.max(0.5 * point.p.dot(&point.v).abs())
    }

    fn extent(point: &PhasePoint<N>) -> Option<f64> {
        Some(point.q.amax())
    }

    fn state(point: &PhasePoint<N>) -> StateSummary {
        StateSummary::Vector {
            q: point.q.iter().copied().collect(),
            v: point.v.iter().copied().collect(),
            p: point.p.iter().copied().collect(),
        }
    }

    fn initial_guess_at_rest(initial: &Initial<N>) -> OVector<f64, N> {
        <Self as Space>::initial_guess(initial)
    }

    fn coordinate_count(initial: &Initial<N>) -> usize {
        initial.position().len()
    }

    /// `t,q_<name>…,v_<name>…,p_<name>…,energy`.
    fn csv_header(model: &L) -> String {
        csv_header(&model.coordinate_names())
    }

    /// t, q, v, p and the energy p·v − L (H for a model without L).
    fn csv_row(model: &L, point: &PhasePoint<N>, row: &mut Vec<f64>) {
        row.push(point.t);
        row.extend(point.q.iter().chain(&point.v).chain(&point.p));
        row.push(model.phase_energy(point.t, &point.q, &point.v, &point.p));
    }
}

impl<L: RigidZooModel> RunSpace<L> for SO3 {
    const LISTS_RUN_FIELDS: bool = false;

    /// Energy, angular momenta about the symmetry axes (for models with axes), the other
    /// invariants (for models with some), and ‖RᵀR − I‖.
    type Diagnostics = (
        Option<EnergyError>,
        Option<AngularMomentumError>,
        Option<InvariantError>,
        Option<OrthogonalityError>,
    );

    /// The invariants and ‖RᵀR − I‖ are measured unless the scene asks for no diagnostic.
    fn diagnostics(model: &L, scene: &Scene) -> Self::Diagnostics {
        let any = scene.measures();
        (
            scene.wants(Diagnostic::Energy).then(EnergyError::default),
            (scene.wants(Diagnostic::Momentum) && model.axis_count() > 0)
                .then(AngularMomentumError::default),
            (any && model.invariant_count() > 0).then(InvariantError::default),
            any.then(OrthogonalityError::default),
        )
    }

    fn measured(
        model: &L,
        (energy, momentum, invariants, orthogonality): Self::Diagnostics,
        _: &RigidPoint,
        last: &RigidPoint,
    ) -> (Option<f64>, Conservation) {
        (
            energy.map(|e| e.max),
            Conservation::Rigid {
                momentum_names: (0..model.axis_count())
                    .map(|i| model.axis_name(i))
                    .collect(),
                momentum_error_max: momentum.as_ref().map(|m| m.max),
                momentum_error_relative: momentum.as_ref().map(AngularMomentumError::relative),
                invariant_names: (0..model.invariant_count())
                    .map(|i| model.invariant_name(i))
                    .collect(),
                invariant_error_max: invariants.map(|i| i.max),
                orthogonality_error_max: orthogonality.map(|o| o.max),
                orthogonality_error_final: orthogonality_error(&last.r),
            },
        )
    }

    fn model_name(model: &L) -> &'static str {
        RigidBodyDefaults::name(model)
    }

    fn parameters(model: &L) -> Vec<(&'static str, f64)> {
        RigidBodyDefaults::parameters(model)
    }

    fn coordinates(_: &L) -> Option<Vec<String>> {
        None
    }

    fn energy(model: &L, point: &RigidPoint) -> f64 {
        RigidBodyExt::energy(model, &point.r, &point.omega)
    }

    /// Rigid bodies here are autonomous and unforced.
    fn conserves_energy(_: &L) -> bool {
        true
    }

    fn energy_scale(model: &L, point: &RigidPoint) -> f64 {
        let energy = <Self as RunSpace<L>>::energy(model, point).abs();
        energy.max(0.5 * point.momentum.dot(&point.omega).abs())
    }

    fn extent(_: &RigidPoint) -> Option<f64> {
        None
    }

    fn state(point: &RigidPoint) -> StateSummary {
        StateSummary::Rigid {
            attitude: point.r.transpose().iter().copied().collect(),
            quaternion: point.quaternion().to_vec(),
            omega: point.omega.iter().copied().collect(),
            momentum: point.momentum.iter().copied().collect(),
            spatial_momentum: point.spatial_momentum().iter().copied().collect(),
        }
    }

    fn initial_guess_at_rest(_: &RigidInitial) -> SVector<f64, 3> {
        SVector::zeros()
    }

    fn coordinate_count(_: &RigidInitial) -> usize {
        3
    }

    /// [`RIGID_CSV_HEADER`].
    fn csv_header(_: &L) -> String {
        RIGID_CSV_HEADER.into()
    }

    /// t, quaternion, R row by row, Ω, Π, energy and ‖RᵀR − I‖_F.
    fn csv_row(model: &L, point: &RigidPoint, row: &mut Vec<f64>) {
        row.push(point.t);
        row.extend(point.quaternion());
        row.extend(point.r.transpose().iter());
        row.extend(point.omega.iter().chain(point.momentum.iter()));
        row.push(RigidBodyExt::energy(model, &point.r, &point.omega));
        row.push(orthogonality_error(&point.r));
    }
}

impl<L, G, const N: usize, const E: usize> RunSpace<L> for GroupSpace<G, N, E>
where
    L: GroupZooModel<N, E, Group = G>,
    G: LieGroup<N, E>,
{
    const LISTS_RUN_FIELDS: bool = false;

    /// Energy, the Noether momenta of the model's symmetry generators (for models with
    /// some), the distance from the exact solution (asked for, and known) and the group
    /// defect.
    type Diagnostics = (
        Option<EnergyError>,
        Option<MomentumError>,
        Option<GroupSolutionError<N, E>>,
        Option<DefectError>,
    );

    /// The group defect is measured unless the scene asks for no diagnostic.
    fn diagnostics(model: &L, scene: &Scene) -> Self::Diagnostics {
        (
            scene.wants(Diagnostic::Energy).then(EnergyError::default),
            (scene.wants(Diagnostic::Momentum) && model.generator_count() > 0)
                .then(MomentumError::default),
            scene
                .wants(Diagnostic::Solution)
                .then(GroupSolutionError::default),
            scene.measures().then(DefectError::default),
        )
    }

    fn measured(
        model: &L,
        (energy, momentum, solution, defect): Self::Diagnostics,
        first: &GroupPoint<N, E>,
        last: &GroupPoint<N, E>,
    ) -> (Option<f64>, Conservation) {
        let scale = first.spatial_momentum::<G>().norm();
        let exact = model.exact_solution(&first.g, &first.xi, last.t - first.t);
        (
            energy.map(|e| e.max),
            Conservation::Group {
                momentum_names: (0..model.generator_count())
                    .map(|i| model.momentum_name(i))
                    .collect(),
                momentum_error_max: momentum.as_ref().map(|m| m.max),
                momentum_error_relative: momentum
                    .as_ref()
                    .map(|m| if scale > 0.0 { m.max / scale } else { m.max }),
                solution_error_max: solution.and_then(|s| s.max),
                solution_error_final: exact.map(|(g, _)| (last.g - g).norm()),
                group_defect_max: defect.map(|d| d.max),
                group_defect_final: G::defect(&last.g),
            },
        )
    }

    fn model_name(model: &L) -> &'static str {
        GroupDefaults::name(model)
    }

    fn parameters(model: &L) -> Vec<(&'static str, f64)> {
        GroupDefaults::parameters(model)
    }

    fn coordinates(_: &L) -> Option<Vec<String>> {
        None
    }

    fn energy(model: &L, point: &GroupPoint<N, E>) -> f64 {
        point.momentum.dot(&point.xi) - model.value(&point.g, &point.xi)
    }

    /// An unforced model on a group is autonomous: it conserves energy.
    fn conserves_energy(_: &L) -> bool {
        !<L as GroupLagrangian<N, E>>::FORCED
    }

    fn energy_scale(model: &L, point: &GroupPoint<N, E>) -> f64 {
        let energy = <Self as RunSpace<L>>::energy(model, point).abs();
        energy.max(0.5 * point.momentum.dot(&point.xi).abs())
    }

    fn extent(_: &GroupPoint<N, E>) -> Option<f64> {
        None
    }

    fn state(point: &GroupPoint<N, E>) -> StateSummary {
        StateSummary::Group {
            g: point.g.iter().copied().collect(),
            xi: point.xi.iter().copied().collect(),
            momentum: point.momentum.iter().copied().collect(),
            spatial_momentum: point.spatial_momentum::<G>().iter().copied().collect(),
        }
    }

    fn initial_guess_at_rest(_: &GroupInitial<N, E>) -> SVector<f64, N> {
        SVector::zeros()
    }

    fn coordinate_count(_: &GroupInitial<N, E>) -> usize {
        N
    }

    /// `t,g_1,…,g_E,xi_1,…,xi_N,mu_1,…,mu_N,energy,defect`.
    fn csv_header(_: &L) -> String {
        let mut header = String::from("t");
        for (prefix, count) in [("g", E), ("xi", N), ("mu", N)] {
            for i in 1..=count {
                header.push_str(&format!(",{prefix}_{i}"));
            }
        }
        header.push_str(",energy,defect\n");
        header
    }

    /// t, g, ξ, μ, the energy μ·ξ − L and the group defect.
    fn csv_row(model: &L, point: &GroupPoint<N, E>, row: &mut Vec<f64>) {
        row.push(point.t);
        row.extend(point.g.iter().chain(&point.xi).chain(&point.momentum));
        row.push(<Self as RunSpace<L>>::energy(model, point));
        row.push(G::defect(&point.g));
    }
}

/// A chain or lattice of the zoo (or written as text) as the run-time-size Lagrangian the
/// methods of ℝⁿ run (its [`Terms`](svi::model::local::Terms): derivatives assembled term by
/// term), with the run's parts of a chain: its few observables in the trajectory, not its n
/// coordinates.
///
/// The chain is an [`AnyChain`], and its declarations are the type's: `TIME_DEPENDENT` and
/// `CONSTANT_MASS` ([`Structure::ConstantMass`](svi::Structure)). The methods are compiled
/// once per declaration, not once per chain ([`AnyChain`]); whoever makes one declares no
/// more than the chain allows (autonomous only where L does not depend on t, constant-mass
/// only where it is).
#[derive(Debug, Clone)]
pub struct Chain<const TIME_DEPENDENT: bool, const CONSTANT_MASS: bool>(pub(crate) AnyChain);

impl<const TIME_DEPENDENT: bool, const CONSTANT_MASS: bool> Chain<TIME_DEPENDENT, CONSTANT_MASS> {
    /// The chain's object-safe parts.
    pub fn model(&self) -> &dyn ChainView {
        self.0.view()
    }
}

impl<const TIME_DEPENDENT: bool, const CONSTANT_MASS: bool> svi::Lagrangian<Dyn>
    for Chain<TIME_DEPENDENT, CONSTANT_MASS>
{
    const TIME_DEPENDENT: bool = TIME_DEPENDENT;
    const STRUCTURE: svi::Structure = if CONSTANT_MASS {
        svi::Structure::ConstantMass
    } else {
        svi::Structure::General
    };

    #[inline]
    fn dimension(&self) -> usize {
        self.model().dimension()
    }

    #[inline]
    fn lagrangian<D: svi::Scalar>(&self, t: D, q: &DVector<D>, v: &DVector<D>) -> D {
        self.0.lagrangian(t, q, v)
    }

    #[inline]
    fn terms(&self) -> Option<&dyn svi::model::TermSum<Dyn>> {
        Some(self.model().terms())
    }
}

impl<const TIME_DEPENDENT: bool, const CONSTANT_MASS: bool> svi::Invariants<Dyn>
    for Chain<TIME_DEPENDENT, CONSTANT_MASS>
{
    fn invariant_count(&self) -> usize {
        self.model().invariant_count()
    }

    fn invariant_name(&self, index: usize) -> &'static str {
        self.model().invariant_name(index)
    }

    fn invariant(&self, index: usize, t: f64, q: &DVector<f64>, v: &DVector<f64>) -> f64 {
        self.model().invariant(index, t, q, v)
    }
}

impl<const TIME_DEPENDENT: bool, const CONSTANT_MASS: bool>
    RunSpace<Chain<TIME_DEPENDENT, CONSTANT_MASS>> for Euclidean<Dyn>
{
    const LISTS_RUN_FIELDS: bool = true;

    /// Energy and the model's invariants (for models with some), each O(n) per step.
    type Diagnostics = (Option<EnergyError>, Option<InvariantError>);

    /// The invariants are measured unless the scene asks for no diagnostic (as on SO(3)).
    fn diagnostics(
        model: &Chain<TIME_DEPENDENT, CONSTANT_MASS>,
        scene: &Scene,
    ) -> Self::Diagnostics {
        (
            scene.wants(Diagnostic::Energy).then(EnergyError::default),
            (scene.measures() && model.model().invariant_count() > 0).then(InvariantError::default),
        )
    }

    fn measured(
        model: &Chain<TIME_DEPENDENT, CONSTANT_MASS>,
        (energy, invariants): Self::Diagnostics,
        _: &PhasePoint<Dyn>,
        _: &PhasePoint<Dyn>,
    ) -> (Option<f64>, Conservation) {
        let model = model.model();
        (
            energy.map(|e| e.max),
            Conservation::Local {
                momentum_error_max: None,
                solution_error_max: None,
                solution_error_final: None,
                invariant_names: (0..model.invariant_count())
                    .map(|i| model.invariant_name(i))
                    .collect(),
                invariant_error_max: invariants.map(|i| i.max),
            },
        )
    }

    fn model_name(model: &Chain<TIME_DEPENDENT, CONSTANT_MASS>) -> &'static str {
        model.model().name()
    }

    fn parameters(model: &Chain<TIME_DEPENDENT, CONSTANT_MASS>) -> Vec<(&'static str, f64)> {
        model.model().parameters()
    }

    /// None: the n coordinates of a chain are numbered, not named.
    fn coordinates(_: &Chain<TIME_DEPENDENT, CONSTANT_MASS>) -> Option<Vec<String>> {
        None
    }

    fn energy(model: &Chain<TIME_DEPENDENT, CONSTANT_MASS>, point: &PhasePoint<Dyn>) -> f64 {
        point.p.dot(&point.v) - model.model().terms().value(point.t, &point.q, &point.v)
    }

    /// Chains have no external force: autonomous ones conserve energy.
    fn conserves_energy(_: &Chain<TIME_DEPENDENT, CONSTANT_MASS>) -> bool {
        !TIME_DEPENDENT
    }

    fn energy_scale(model: &Chain<TIME_DEPENDENT, CONSTANT_MASS>, point: &PhasePoint<Dyn>) -> f64 {
        let energy =
            <Self as RunSpace<Chain<TIME_DEPENDENT, CONSTANT_MASS>>>::energy(model, point).abs();
        energy.max(0.5 * point.p.dot(&point.v).abs())
    }

    fn extent(point: &PhasePoint<Dyn>) -> Option<f64> {
        Some(point.q.amax())
    }

    fn state(point: &PhasePoint<Dyn>) -> StateSummary {
        StateSummary::Vector {
            q: point.q.iter().copied().collect(),
            v: point.v.iter().copied().collect(),
            p: point.p.iter().copied().collect(),
        }
    }

    fn initial_guess_at_rest(initial: &Initial<Dyn>) -> DVector<f64> {
        <Self as Space>::initial_guess(initial)
    }

    fn coordinate_count(initial: &Initial<Dyn>) -> usize {
        initial.position().len()
    }

    /// `t,energy,<observables>`: the model's few observables (FPUT: the mode energies
    /// `mode_1`, …; Toda: the Lax traces), not the n coordinates.
    fn csv_header(model: &Chain<TIME_DEPENDENT, CONSTANT_MASS>) -> String {
        let mut header = String::from("t,energy");
        for name in model.model().observable_names() {
            header.push(',');
            header.push_str(&name);
        }
        header.push('\n');
        header
    }

    /// t, the energy p·v − L and the observables.
    fn csv_row(
        model: &Chain<TIME_DEPENDENT, CONSTANT_MASS>,
        point: &PhasePoint<Dyn>,
        row: &mut Vec<f64>,
    ) {
        row.push(point.t);
        row.push(<Self as RunSpace<Chain<TIME_DEPENDENT, CONSTANT_MASS>>>::energy(model, point));
        model
            .model()
            .observables_into(point.t, &point.q, &point.v, row);
    }
}
