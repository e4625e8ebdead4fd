//! [`AnyChain`]: every chain and lattice of the zoo, and every chain written as text, as one
//! type chosen at run time.
//!
//! A chain reaches the methods of ℝⁿ as [`Terms`] of its [`LocalLagrangian`], and every
//! derivative a method takes of it goes through the terms' [`TermSum`] (a trait object: one
//! virtual call per batch of terms or per term). What the chain's own type decides beyond
//! that is only the generic value [`AnyChain::lagrangian`] and the declarations
//! ([`LocalLagrangian::TIME_DEPENDENT`], [`LocalLagrangian::STRUCTURE`]). A program that runs
//! a chain chosen by name therefore compiles its methods once per *declaration* on
//! `AnyChain` (the command line: three) instead of once per chain type (fourteen), and each
//! step runs the same term code either way.

use nalgebra::DVector;
use svi::model::TermSum;
use svi::model::local::{LocalDefaults, LocalInvariants, LocalLagrangian, Terms};
use svi::model::text::TextChain;
use svi::{Dyn, Lagrangian, Scalar, Structure};

use crate::{Fput, FputStiff, LocalZooModel, Polymer, RelativisticChain, SineGordonChain, Toda};

/// What a run needs of a chain besides its generic value, as a trait object: its terms, its
/// declarations, defaults, invariants and observables (implemented for the [`Terms`] of
/// every [`LocalZooModel`]).
pub trait ChainView: Send + Sync {
    /// The chain's terms, for [`Lagrangian::terms`].
    fn terms(&self) -> &dyn TermSum<Dyn>;
    /// The number of coordinates n.
    fn dimension(&self) -> usize;
    /// [`LocalLagrangian::TIME_DEPENDENT`].
    fn time_dependent(&self) -> bool;
    /// [`LocalLagrangian::STRUCTURE`].
    fn structure(&self) -> Structure;
    /// [`LocalDefaults::name`].
    fn name(&self) -> &'static str;
    /// [`LocalDefaults::parameters`].
    fn parameters(&self) -> Vec<(&'static str, f64)>;
    /// [`LocalInvariants::invariant_count`].
    fn invariant_count(&self) -> usize;
    /// [`LocalInvariants::invariant_name`].
    fn invariant_name(&self, index: usize) -> &'static str;
    /// [`LocalInvariants::invariant`].
    fn invariant(&self, index: usize, t: f64, q: &DVector<f64>, v: &DVector<f64>) -> f64;
    /// [`LocalZooModel::observable_names`].
    fn observable_names(&self) -> Vec<String>;
    /// [`LocalZooModel::observables_into`].
    fn observables_into(&self, t: f64, q: &DVector<f64>, v: &DVector<f64>, out: &mut Vec<f64>);
}

impl<M: LocalZooModel> ChainView for Terms<M> {
    fn terms(&self) -> &dyn TermSum<Dyn> {
        &self.0
    }

    fn dimension(&self) -> usize {
        LocalLagrangian::dimension(&self.0)
    }

    fn time_dependent(&self) -> bool {
        M::TIME_DEPENDENT
    }

    fn structure(&self) -> Structure {
        M::STRUCTURE
    }

    fn name(&self) -> &'static str {
        LocalDefaults::name(&self.0)
    }

    fn parameters(&self) -> Vec<(&'static str, f64)> {
        LocalDefaults::parameters(&self.0)
    }

    fn invariant_count(&self) -> usize {
        LocalInvariants::invariant_count(&self.0)
    }

    fn invariant_name(&self, index: usize) -> &'static str {
        LocalInvariants::invariant_name(&self.0, index)
    }

    fn invariant(&self, index: usize, t: f64, q: &DVector<f64>, v: &DVector<f64>) -> f64 {
        LocalInvariants::invariant(&self.0, index, t, q, v)
    }

    fn observable_names(&self) -> Vec<String> {
        LocalZooModel::observable_names(&self.0)
    }

    fn observables_into(&self, t: f64, q: &DVector<f64>, v: &DVector<f64>, out: &mut Vec<f64>) {
        LocalZooModel::observables_into(&self.0, t, q, v, out);
    }
}

/// The enum and its two dispatches, from one list of variants.
macro_rules! any_chain {
    ($($variant:ident($model:ty)),+ $(,)?) => {
        /// A chain of the zoo or written as text, whichever it is (see the module
        /// documentation); every [`LocalZooModel`] converts into one.
        #[derive(Debug, Clone)]
        pub enum AnyChain {
            $(
                #[doc = concat!("[`", stringify!($model), "`] as [`Terms`].")]
                $variant(Terms<$model>),
            )+
        }

        $(
            impl From<$model> for AnyChain {
                fn from(model: $model) -> Self {
                    AnyChain::$variant(Terms(model))
                }
            }
        )+

        impl AnyChain {
            /// The chain behind its object-safe parts.
            #[inline]
            pub fn view(&self) -> &dyn ChainView {
                match self {
                    $(AnyChain::$variant(terms) => terms,)+
                }
            }

            /// L(t, q, q̇) = Σₑ ℓₑ in any scalar, term by term ([`Terms`]' value).
            #[inline]
            pub fn lagrangian<D: Scalar>(&self, t: D, q: &DVector<D>, v: &DVector<D>) -> D {
                match self {
                    $(AnyChain::$variant(terms) => terms.lagrangian(t, q, v),)+
                }
            }
        }
    };
}

any_chain!(
    Fput(Fput),
    FputStiff(FputStiff),
    Toda(Toda),
    RelativisticChain(RelativisticChain),
    SineGordonChain(SineGordonChain),
    Polymer(Polymer),
    Text1(TextChain<1, false, true>),
    Text2(TextChain<2, false, true>),
    Text3(TextChain<3, false, true>),
    Text4(TextChain<4, false, true>),
    Text1General(TextChain<1>),
    Text2General(TextChain<2>),
    Text3General(TextChain<3>),
    Text4General(TextChain<4>),
);

#[cfg(test)]
mod tests {
    use super::*;
    use svi::model::text::{TextChainModel, TextSpec};

    /// The erased chain has the chain's value, gradient, declarations and names, and its
    /// generic value carries the chain's derivatives.
    #[test]
    fn an_erased_chain_is_the_chain() {
        let fput = Fput::default();
        let n = LocalLagrangian::dimension(&fput);
        let q = DVector::from_fn(n, |i, _| 0.1 * (i as f64 + 1.0).sin());
        let v = DVector::from_fn(n, |i, _| 0.2 * (i as f64 + 0.5).cos());
        let chain = AnyChain::from(fput.clone());
        assert_eq!(chain.view().name(), "fput");
        assert_eq!(chain.view().dimension(), n);
        assert!(!chain.view().time_dependent());
        assert_eq!(chain.view().structure(), Structure::ConstantMass);
        let value = LocalLagrangian::value(&fput, 0.0, &q, &v);
        assert_eq!(chain.view().terms().value(0.0, &q, &v), value);
        assert!((chain.lagrangian(0.0, &q, &v) - value).abs() < 1e-14 * value.abs());
        // ∂L/∂q₃ by a dual number against the terms' gradient.
        let mut force = DVector::zeros(n);
        chain
            .view()
            .terms()
            .gradient_into(0.0, &q, &v, svi::dimension::Wrt::Position, &mut force);
        let seeded = DVector::from_fn(n, |i, _| {
            num_dual::Dual64::new(q[i], if i == 3 { 1.0 } else { 0.0 })
        });
        let lifted = v.map(num_dual::Dual64::from);
        let dual = chain.lagrangian(num_dual::Dual64::from(0.0), &seeded, &lifted);
        assert!((dual.eps - force[3]).abs() < 1e-13);

        let spec = TextSpec {
            lagrangian: "sum(i, 1, n, 0.5*(1 + 0.1*t)*vq[i]^2) - sum(i, 0, n, 0.5*(q[i+1]-q[i])^2)"
                .into(),
            coordinates: vec!["q[1..n]".into()],
            parameters: vec![("n".into(), 5.0)],
            ..TextSpec::default()
        };
        let model = TextChainModel::new(&spec).unwrap();
        let text = AnyChain::from(TextChain::<2>::new(model).unwrap());
        assert!(text.view().time_dependent());
        assert_eq!(text.view().structure(), Structure::General);
    }
}
