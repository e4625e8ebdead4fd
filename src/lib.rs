//! # svi — structure-preserving simulation from one Lagrangian
//!
//! Write a Lagrangian once, generic over [`Scalar`]; `svi` derives everything each integrator
//! needs by automatic differentiation (num-dual):
//!
//! - [`Svi`]: Galerkin spectral variational integrators (Li, Wu, Leok 2018, eqs. 6–11):
//!   Chebyshev–Gauss–Lobatto interpolation, Gauss–Legendre quadrature, exact Newton Jacobian
//!   from the Hessian blocks of L. Symplectic, momentum-preserving.
//! - [`SpectralCollocation`]: spectral collocation of the Euler–Lagrange equations (eqs.
//!   12–25), q̈ = f(t, q, q̇) and its Jacobian derived from L.
//!
//! Both run through one stepping loop, [`Integrator`], with opt-in [`observer`]s.
//!
//! Rigid bodies live on SO(3) instead of ℝᴺ: [`lie_group`] takes a Lagrangian L(R, Ω) on the
//! group and integrates it with the higher-order Lie-group variational integrator
//! ([`lie_group::LieSvi`], natural charts and interpolation in the Lie algebra, Leok §5.3;
//! the reduced discrete Euler–Poincaré form for G-invariant L, §5.4), through its own
//! stepping loop and observers ([`lie_group::RigidBodyIntegrator`]).
//!
//! Field theories in 1 + 1 dimensions are written as a Lagrangian density ℒ(x, t, u, u_t, u_x)
//! ([`model::density`]) and integrated by the multisymplectic variational integrator of
//! [`field`] (Leok §5.1.3): bilinear elements on a space-time mesh, explicit leapfrog or sparse
//! Newton per time level, with the discrete multisymplectic conservation law as a diagnostic.
//!
//! ```
//! use nalgebra::{SVector, U1};
//! use svi::{Integrator, Lagrangian, Scalar, Svi};
//!
//! /// Harmonic oscillator L = q̇²/2 − q²/2.
//! struct Oscillator;
//! impl Lagrangian<U1> for Oscillator {
//!     const TIME_DEPENDENT: bool = false;
//!     fn lagrangian<D: Scalar>(&self, _t: D, q: &SVector<D, 1>, v: &SVector<D, 1>) -> D {
//!         (v[0] * v[0] - q[0] * q[0]) * 0.5
//!     }
//! }
//!
//! let integrator = Integrator::new(Oscillator, Svi::default());
//! let run = integrator
//!     .run_from_velocity(0.0, SVector::from([1.0]), SVector::from([0.0]), 0.1, 1.0, &mut ())
//!     .unwrap();
//! assert!((run.last.q[0] - 1f64.cos()).abs() < 1e-12);
//! ```

// The layers, bottom up; each imports only from the ones above it in this list.
pub mod analysis;
pub mod dimension;
pub mod error;
pub mod field;
pub mod lie_group;
pub mod linalg;
pub mod method;
pub mod model;
mod nonlinear;
pub mod scalar;
pub mod spectral;
pub mod stepping;
#[cfg(test)]
mod test_models;

// Module paths of earlier releases, kept for users' code.
pub use analysis::chaos;
pub use analysis::{drift, sensitivity, stability, verify};
pub use model::derived;
pub use spectral::{basis, quadrature};
pub use stepping::{observer, solve};

pub use derived::LagrangianExt;
pub use dimension::{Dimension, Dyn};
pub use error::Error;
pub use method::collocation::SpectralCollocation;
pub use method::registry::MethodSpec;
pub use method::variational::composition::{Composition, Scheme};
pub use method::variational::discrete_lagrangian::{
    AdjointSymplecticEuler, DiscreteLagrangian, Midpoint, SymplecticEuler, Trapezoid,
};
pub use method::variational::stormer_verlet::StormerVerlet;
pub use method::variational::svi::{Solver, Svi};
pub use method::variational::variational_integrator::VariationalIntegrator;
pub use method::{
    Coordinates, Equations, Euclidean, Initial, Method, MethodInfo, PhasePoint, SO3, Space, State,
    Step, StepAdjoint, TangentMap,
};
pub use model::hamiltonian::{Canonical, Hamiltonian, HamiltonianStructure};
pub use model::parametric::Parametric;
pub use model::text::{TextError, TextHamiltonian, TextLagrangian, TextModel, TextSpec};
pub use model::{Defaults, ExactSolution, Invariants, Lagrangian, Structure, Symmetries};
pub use scalar::Scalar;
pub use stepping::grid::step_count;
pub use stepping::run::{Integrator, Recovery, RunOptions, Statistics};
pub use stepping::solve::{Adapt, SolveOptions, Span, solve};

/// A run on ℝᴺ: [`stepping::run::Run`] on [`Euclidean<N>`] (`N` = `U2`, …, or [`Dyn`]).
pub type Run<N> = stepping::run::Run<Euclidean<N>>;
/// A failed run on ℝᴺ: [`stepping::run::RunFailure`] on [`Euclidean<N>`].
pub type RunFailure<N> = stepping::run::RunFailure<Euclidean<N>>;
/// A solution on ℝᴺ: [`stepping::solve::Solution`] on [`Euclidean<N>`].
pub type Solution<N> = stepping::solve::Solution<Euclidean<N>>;

/// The README's examples, compiled and run as doctests.
#[doc = include_str!("../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;

/// One item per chapter of the guide (`docs/guide/src`) with Rust code blocks, whose examples
/// are compiled and run as doctests as the README's are; `GUIDE_DOCTESTS` names the chapters,
/// and a test checks that every chapter with Rust code is among them.
macro_rules! guide_doctests {
    ($($item:ident: $chapter:literal),* $(,)?) => {
        $(
            #[doc = include_str!(concat!("../docs/guide/src/", $chapter))]
            #[cfg(doctest)]
            pub struct $item;
        )*
        /// The chapters of the guide whose Rust code blocks run as doctests.
        #[cfg(test)]
        const GUIDE_DOCTESTS: &[&str] = &[$($chapter),*];
    };
}

guide_doctests! {
    GuideRustDoctests: "rust.md",
    GuideAdaptivityDoctests: "adaptivity.md",
    GuideStressDoctests: "stress.md",
    GuideConstraintsDoctests: "constraints.md",
    GuideChaosDoctests: "chaos.md",
    GuideHamiltonianDoctests: "hamiltonian.md",
    GuideRigidBodiesDoctests: "rigid-bodies.md",
    GuideSensitivitiesDoctests: "sensitivities.md",
}

#[cfg(test)]
mod guide_tests {
    /// Whether a fenced code block's info string makes rustdoc compile it: no language, or
    /// `rust` among its comma-separated attributes.
    fn is_rust(info: &str) -> bool {
        info.is_empty() || info.split(',').any(|attribute| attribute.trim() == "rust")
    }

    #[test]
    fn every_guide_chapter_with_rust_code_runs_its_doctests() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/guide/src");
        let mut with_rust = Vec::new();
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_none_or(|extension| extension != "md") {
                continue;
            }
            let text = std::fs::read_to_string(&path).unwrap();
            let mut in_block = false;
            let mut rust = false;
            for line in text.lines() {
                if let Some(info) = line.trim_start().strip_prefix("```") {
                    if !in_block && is_rust(info.trim()) {
                        rust = true;
                    }
                    in_block = !in_block;
                }
            }
            assert!(!in_block, "{}: a code block is not closed", path.display());
            if rust {
                with_rust.push(path.file_name().unwrap().to_str().unwrap().to_owned());
            }
        }
        with_rust.sort();
        let mut listed = super::GUIDE_DOCTESTS.to_vec();
        listed.sort();
        assert_eq!(
            with_rust, listed,
            "guide chapters with Rust code blocks (src/lib.rs)"
        );
    }
}
