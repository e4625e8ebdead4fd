//! Symmetric compositions of Störmer–Verlet: higher order from the second-order method.
//!
//! # The composition
//! With Φ_h one step of [`StormerVerlet`] (order 2, symmetric; or of Störmer–Verlet on
//! Hamilton's equations, [`crate::method::hamiltonian::Partitioned::stormer_verlet`], any base
//! that is [`Composable`]), the composition
//!
//! Ψ_h = Φ_{γ_s h} ∘ … ∘ Φ_{γ_1 h},  Σ γ_i = 1, γ_i = γ_{s+1−i},
//!
//! is symmetric, and of order p when the γ_i solve the order conditions of Yoshida (1990) and
//! Suzuki (1990) (Hairer, Lubich, Wanner, *Geometric numerical integration*, §II.4 and
//! §V.3). A composition of symplectic maps is symplectic, and a composition of variational
//! integrators is the variational integrator of the composed discrete Lagrangian
//! L_d(q_0, q_s) = Σ_i L_d^{γ_i h}(q_{i−1}, q_i) extremised over the inner q_i (Marsden &
//! West, *Discrete mechanics and variational integrators*, Acta Numerica 2001, on composition
//! methods), so every property of Störmer–Verlet but its order carries over: momenta of
//! symmetries conserved, energy error bounded (by backward error analysis) for the whole run.
//!
//! The schemes ([`Scheme`]):
//! - `yoshida4`: the "triple jump" γ = (γ₁, 1 − 2γ₁, γ₁), γ₁ = 1/(2 − 2^{1/3}), order 4,
//!   3 stages (Yoshida 1990; Forest & Ruth 1990);
//! - `kahan-li6`: order 6, 9 stages (Kahan & Li, "Composition constants for raising the
//!   orders of unconventional schemes for ordinary differential equations", Math. Comp. 66
//!   (1997) 1089, scheme p6 s9);
//! - `kahan-li8`: order 8, 17 stages (Kahan & Li 1997, scheme p8 s17).
//!
//! On a constant-mass Lagrangian every stage costs one gradient ∂L/∂q: the force at the end of
//! a stage is Störmer–Verlet's force at the start of the next one (its cache recognises the
//! point), so a step of s stages costs s gradients. Other Lagrangians take Störmer–Verlet's
//! implicit path at every stage. The observed orders are tested on the Kepler problem
//! (`tests/logh.rs`) and the FPUT chain (`tests/local.rs`).
//!
//! The same coefficients split the logarithmic Hamiltonian of a time-reparametrised run
//! ([`crate::stepping::logh`]).

use crate::dimension::{Dimension, dimension_of};
use crate::error::{Error, StepFailure};
use crate::method::space::StepState;
use crate::method::variational::stormer_verlet::{StormerVerlet, StormerVerletWorkspace};
use crate::method::{Method, MethodInfo, State, StepReport, TangentMap};
use crate::model::Lagrangian;
use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, OVector};

/// A symmetric composition scheme: its name and the step fractions γ_1, …, γ_s.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scheme {
    /// Yoshida's triple jump, order 4, 3 stages.
    Yoshida4,
    /// Kahan & Li p6 s9, order 6, 9 stages.
    KahanLi6,
    /// Kahan & Li p8 s17, order 8, 17 stages.
    KahanLi8,
}

/// γ_1, …, γ_m of a symmetric scheme with an odd number 2m − 1 of stages (γ_m the middle
/// one), mirrored to all 2m − 1.
fn mirrored<const M: usize>(half: [f64; M]) -> Vec<f64> {
    half.iter()
        .chain(half[..M - 1].iter().rev())
        .copied()
        .collect()
}

impl Scheme {
    /// Every scheme, by order.
    pub const ALL: [Scheme; 3] = [Scheme::Yoshida4, Scheme::KahanLi6, Scheme::KahanLi8];

    /// The scheme of a registry name (`yoshida4`, `kahan-li6`, `kahan-li8`).
    pub fn named(name: &str) -> Option<Scheme> {
        Scheme::ALL.into_iter().find(|scheme| scheme.name() == name)
    }

    /// The name in the method registry (`yoshida4`, `kahan-li6`, `kahan-li8`).
    pub fn name(self) -> &'static str {
        match self {
            Scheme::Yoshida4 => "yoshida4",
            Scheme::KahanLi6 => "kahan-li6",
            Scheme::KahanLi8 => "kahan-li8",
        }
    }

    /// The order p.
    pub fn order(self) -> usize {
        match self {
            Scheme::Yoshida4 => 4,
            Scheme::KahanLi6 => 6,
            Scheme::KahanLi8 => 8,
        }
    }

    /// The step fractions γ_1, …, γ_s (symmetric, summing to 1).
    // The constants keep the published digits, beyond what an f64 holds.
    #[allow(clippy::excessive_precision)]
    pub fn fractions(self) -> Vec<f64> {
        match self {
            Scheme::Yoshida4 => {
                let outer = 1.0 / (2.0 - 2f64.cbrt());
                vec![outer, 1.0 - 2.0 * outer, outer]
            }
            // Kahan & Li (1997), scheme p6 s9: γ_1 … γ_5 (γ_5 the middle one).
            Scheme::KahanLi6 => mirrored([
                0.392_161_444_007_314_139_279_250_56,
                0.332_599_136_789_359_438_599_748_64,
                -0.706_246_172_557_639_359_809_964_82,
                0.082_213_596_293_550_800_231_490_45,
                0.798_543_990_934_829_963_398_950_35,
            ]),
            // Kahan & Li (1997), scheme p8 s17: γ_1 … γ_9 (γ_9 the middle one).
            Scheme::KahanLi8 => mirrored([
                0.130_202_483_088_890_080_878_817_63,
                0.561_162_981_775_108_384_561_964_41,
                -0.389_474_962_644_847_286_408_078_60,
                0.158_841_906_555_155_600_896_210_75,
                -0.395_903_894_133_237_577_336_231_54,
                0.184_539_640_978_315_707_091_832_54,
                0.258_374_387_686_322_047_293_979_11,
                0.295_011_723_609_310_298_870_966_24,
                -0.605_508_533_830_034_511_698_921_08,
            ]),
        }
    }
}

/// A symmetric method of order 2 that the schemes compose: Störmer–Verlet on L or on H.
pub trait Composable {
    /// The registry name of the composition `scheme` of this method.
    fn composed_name(&self, scheme: Scheme) -> &'static str;
}

impl Composable for StormerVerlet {
    /// `yoshida4`, `kahan-li6`, `kahan-li8`.
    fn composed_name(&self, scheme: Scheme) -> &'static str {
        scheme.name()
    }
}

/// Options of a composition of Störmer–Verlet (see the module docs): of the Lagrangian
/// [`StormerVerlet`] by default. The scheme is fixed at construction: the step fractions are
/// derived from it once.
#[derive(Debug, Clone, PartialEq)]
pub struct Composition<B = StormerVerlet> {
    scheme: Scheme,
    /// The base method (its options).
    pub base: B,
    fractions: Vec<f64>,
}

impl Composition {
    /// The composition `scheme` of Störmer–Verlet with its default options.
    pub fn new(scheme: Scheme) -> Self {
        Composition::with_base(scheme, StormerVerlet::default())
    }
}

impl<B> Composition<B> {
    /// The composition `scheme` of `base`, a symmetric method of order 2.
    pub fn with_base(scheme: Scheme, base: B) -> Self {
        Composition {
            scheme,
            base,
            fractions: scheme.fractions(),
        }
    }

    /// The scheme.
    pub fn scheme(&self) -> Scheme {
        self.scheme
    }

    /// The step fractions γ_1, …, γ_s.
    pub fn fractions(&self) -> &[f64] {
        &self.fractions
    }

    /// The stages of a step of size `h` from `state` at `t`, on any state space: `step(t_i,
    /// γ_i h, from, increment)` takes stage i from `from` = state + the sum of the increments
    /// before it and writes its increment; `total` receives the sum of all of them, the
    /// step's increment (one rounding of the state per step, as for any other method).
    /// `from` and `stage` are scratch of the state's shape: nothing is allocated.
    pub(crate) fn stages<S: StepState>(
        &self,
        (t, h): (f64, f64),
        state: &S,
        (from, stage, total): (&mut S, &mut S, &mut S),
        mut step: impl FnMut(f64, f64, &S, &mut S) -> Result<(), StepFailure>,
    ) -> Result<(), StepFailure> {
        let mut elapsed = 0.0;
        for (i, gamma) in self.fractions.iter().enumerate() {
            let size = gamma * h;
            from.assign(state);
            if i > 0 {
                from.add(total);
            }
            step(t + elapsed, size, from, stage)?;
            if i == 0 {
                total.assign(stage);
            } else {
                total.add(stage);
            }
            elapsed += size;
        }
        Ok(())
    }
}

/// Buffers of a composition run: the base method's (Störmer–Verlet's by default), and the
/// start and increment of one stage.
#[derive(Debug, Clone)]
pub struct CompositionWorkspace<N: Dimension, W = StormerVerletWorkspace<N>>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    base: W,
    from: State<N>,
    stage: State<N>,
}

impl<N: Dimension, B: Method<N> + Composable> Method<N> for Composition<B>
where
    DefaultAllocator: Allocator<N> + Allocator<N, N>,
{
    const WITHOUT_POINTS: bool = true;
    const COMPOSES_VERLET: bool = B::COMPOSES_VERLET;

    type Workspace = CompositionWorkspace<N, B::Workspace>;

    /// The base method's properties with the scheme's name and order.
    fn info(&self) -> MethodInfo {
        MethodInfo {
            name: self.base.composed_name(self.scheme),
            order: self.scheme.order(),
            ..Method::<N>::info(&self.base)
        }
    }

    fn workspace<L: Lagrangian<N>>(
        &self,
        model: &L,
        h: f64,
    ) -> Result<CompositionWorkspace<N, B::Workspace>, Error> {
        let base = self.base.workspace(model, h)?;
        let n: N =
            dimension_of(model.dimension()).map_err(|reason| Error::invalid("model", reason))?;
        Ok(CompositionWorkspace {
            base,
            from: State::zeros(n),
            stage: State::zeros(n),
        })
    }

    /// The stages in turn, each from where the last ended.
    fn step<L: Lagrangian<N>>(
        &self,
        model: &L,
        workspace: &mut CompositionWorkspace<N, B::Workspace>,
        t: f64,
        h: f64,
        state: &State<N>,
        increment: &mut State<N>,
    ) -> Result<StepReport, StepFailure> {
        let CompositionWorkspace { base, from, stage } = workspace;
        let mut report = StepReport::default();
        self.stages(
            (t, h),
            state,
            (from, stage, increment),
            |t, size, from, stage| {
                report += self.base.step(model, base, t, size, from, stage)?;
                Ok(())
            },
        )?;
        Ok(report)
    }

    /// The fractions, if the base is the Störmer–Verlet step the logarithmic-Hamiltonian
    /// splitting reproduces.
    fn verlet_fractions(&self) -> Option<&[f64]> {
        Method::<N>::verlet_fractions(&self.base).map(|_| self.fractions.as_slice())
    }

    fn keeps_sparsity<L: Lagrangian<N>>(&self, model: &L) -> bool {
        Method::<N>::keeps_sparsity(&self.base, model)
    }

    fn restart(&self, workspace: &mut CompositionWorkspace<N, B::Workspace>) {
        Method::<N>::restart(&self.base, &mut workspace.base);
    }

    fn velocity_into<L: Lagrangian<N>>(
        &self,
        model: &L,
        workspace: &CompositionWorkspace<N, B::Workspace>,
        t: f64,
        q: &OVector<f64, N>,
        p: &OVector<f64, N>,
        v: &mut OVector<f64, N>,
    ) -> Result<bool, Error> {
        self.base.velocity_into(model, &workspace.base, t, q, p, v)
    }

    /// The product of the stages' tangent maps.
    fn tangent_map<L: Lagrangian<N>>(
        &self,
        model: &L,
        workspace: &mut CompositionWorkspace<N, B::Workspace>,
        t: f64,
        h: f64,
        state: &State<N>,
    ) -> Result<(State<N>, TangentMap<N>, StepReport), StepFailure> {
        let base = &mut workspace.base;
        let mut product: Option<TangentMap<N>> = None;
        let mut report = StepReport::default();
        let n = state.dimension();
        let (mut from, mut stage, mut total) = (State::zeros(n), State::zeros(n), State::zeros(n));
        self.stages(
            (t, h),
            state,
            (&mut from, &mut stage, &mut total),
            |t, size, from, stage| {
                let (increment, tangent, work) =
                    self.base.tangent_map(model, base, t, size, from)?;
                *stage = increment;
                report += work;
                product = Some(match &product {
                    None => tangent,
                    Some(before) => before.then(&tangent),
                });
                Ok(())
            },
        )?;
        product
            .map(|tangent| (total, tangent, report))
            .ok_or(StepFailure::SingularMatrix)
    }
}
