//! The library's methods by name: a registry as data and one dispatch.
//!
//! [`METHODS`] lists every method with its name, the numeric options its name takes, the
//! space it integrates on and a one-line summary. A [`MethodSpec`] is one entry with its
//! options, written and parsed in one grammar:
//!
//! - `name` — the method with its default options (`svi`, `midpoint`, `lie-svi`);
//! - `name:P` — P Chebyshev–Gauss–Lobatto points (`svi:7`, `sc:9`, `lie-svi-reduced:3`);
//! - `name:P/M` — and M Gauss–Legendre points (`svi:7/6`, `lie-svi:3/3`).
//!
//! A spec becomes a method in one place: [`MethodSpec::vector_method`] builds a method for
//! models on ℝᴺ ([`crate::Lagrangian`]) as an [`AnyMethod`] ([`MethodSpec::visit_vector`]
//! hands it on as its own type), and [`MethodSpec::lie_svi`] builds the rigid-body method on SO(3)
//! ([`crate::lie_group::RigidBodyLagrangian`]). Adding a method touches its own file, one
//! entry of [`METHODS`], one arm of one of those two functions and, on ℝᴺ, one variant of
//! [`AnyMethod`].
//!
//! ```
//! use svi::MethodSpec;
//!
//! let spec: MethodSpec = "svi:7/6".parse().unwrap();
//! assert_eq!((spec.name(), spec.points(), spec.quadrature()), ("svi", Some(7), Some(6)));
//! assert_eq!(spec.to_string(), "svi:7/6");
//! assert_eq!(spec.info().unwrap().order, 12);
//! assert!("midpoint:3".parse::<MethodSpec>().is_err());
//! ```

use std::fmt;
use std::str::FromStr;

use crate::dimension::Dimension;
use crate::error::Error;
use crate::method::any::AnyMethod;
pub use crate::method::any::VectorMethodVisitor;
use crate::method::collocation::SpectralCollocation;
use crate::method::hamiltonian::{
    HamiltonianCollocation, HamiltonianGalerkin, ImplicitMidpoint, Partitioned,
};
use crate::method::lie_svi::{Form, LieSvi};
use crate::method::multiscale::Multiscale;
use crate::method::reference::{ExplicitEuler, ImplicitEuler, RungeKutta4};
use crate::method::variational::composition::{Composition, Scheme};
use crate::method::variational::discrete_lagrangian::{
    AdjointSymplecticEuler, Midpoint, SymplecticEuler, Trapezoid,
};
use crate::method::variational::stormer_verlet::StormerVerlet;
use crate::method::variational::svi::{Solver, Svi};
use crate::method::variational::variational_integrator::VariationalIntegrator;
use crate::method::{Equations, Method, MethodInfo};
use crate::spectral::{check_points, check_quadrature};
use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, U1};

/// The numeric options a method's name takes in the grammar, with their defaults (read off
/// the method type's `Default`).
#[derive(Debug, Clone, Copy)]
pub enum Options {
    /// No options: `name` only.
    None,
    /// Chebyshev–Gauss–Lobatto points: `name` or `name:P`.
    Points {
        /// P when it is omitted.
        default: fn() -> usize,
    },
    /// Chebyshev–Gauss–Lobatto and Gauss–Legendre points: `name`, `name:P` or `name:P/M`.
    PointsAndQuadrature {
        /// P when it is omitted.
        default_points: fn() -> usize,
        /// M when it is omitted, as a function of P.
        default_quadrature: fn(usize) -> usize,
    },
}

/// The configuration space of the models a method integrates.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SpaceKind {
    /// Models on ℝᴺ ([`crate::Lagrangian`]), run by [`crate::Integrator`].
    Vector,
    /// Models on Lie groups: rigid bodies on SO(3)
    /// ([`crate::lie_group::RigidBodyLagrangian`], run by
    /// [`crate::lie_group::RigidBodyIntegrator`]) and models on any group
    /// ([`crate::lie_group::GroupLagrangian`], run by [`crate::lie_group::GroupIntegrator`]).
    Group,
}

/// One method of the registry.
#[derive(Debug, Clone, Copy)]
pub struct Entry {
    /// The name, as written in scenes and on the command line (also the name in the built
    /// method's [`MethodInfo`]).
    pub name: &'static str,
    /// The numeric options the name takes.
    pub options: Options,
    /// The space the method integrates on.
    pub space: SpaceKind,
    /// One line of plain text: what the method is and what its options mean.
    pub summary: &'static str,
}

/// The options of `svi` and `svi-newton` (one method, two solvers).
const SVI_OPTIONS: Options = Options::PointsAndQuadrature {
    default_points: || Svi::default().points,
    default_quadrature: |points| Svi::new(points).quadrature_points(),
};

/// Every method of the library, in the order help texts list them.
pub const METHODS: &[Entry] = &[
    Entry {
        name: "svi",
        options: SVI_OPTIONS,
        space: SpaceKind::Vector,
        summary: "spectral variational integrator: CGL points P, Gauss points M (default 2P, at most 256)",
    },
    Entry {
        name: "svi-newton",
        options: SVI_OPTIONS,
        space: SpaceKind::Vector,
        summary: "svi with Newton's method and the exact Jacobian at every iteration, also for \
                  constant-mass models: CGL points P, Gauss points M (default 2P)",
    },
    Entry {
        name: "svi-h",
        options: Options::PointsAndQuadrature {
            default_points: || HamiltonianGalerkin::default().points,
            default_quadrature: |points| Svi::new(points).quadrature_points(),
        },
        space: SpaceKind::Vector,
        summary: "Galerkin Hamiltonian variational integrator on Hamilton's equations (svi's map \
                  for a hyperregular L; svi's fixed point for H = ½pᵀM⁻¹p + V, Newton on the \
                  Gauss-point momenta otherwise): CGL points P, Gauss points M (default 2P)",
    },
    Entry {
        name: "sc",
        options: Options::Points {
            default: || SpectralCollocation::default().points,
        },
        space: SpaceKind::Vector,
        summary: "spectral collocation of the Euler–Lagrange equations: CGL points P",
    },
    Entry {
        name: "sc-h",
        options: Options::Points {
            default: || HamiltonianCollocation::default().points,
        },
        space: SpaceKind::Vector,
        summary: "spectral collocation of Hamilton's equations in (q, p): CGL points P",
    },
    Entry {
        name: "symplectic-euler",
        options: Options::None,
        space: SpaceKind::Vector,
        summary: "symplectic Euler, L_d = h L(q_k, v), explicit for constant-mass models",
    },
    Entry {
        name: "symplectic-euler-adjoint",
        options: Options::None,
        space: SpaceKind::Vector,
        summary: "adjoint symplectic Euler, L_d = h L(q_k+1, v), explicit for constant-mass models",
    },
    Entry {
        name: "midpoint",
        options: Options::None,
        space: SpaceKind::Vector,
        summary: "midpoint rule, L_d = h L((q_k + q_k+1)/2, v)",
    },
    Entry {
        name: "verlet",
        options: Options::None,
        space: SpaceKind::Vector,
        summary: "Störmer–Verlet, explicit for constant-mass models",
    },
    Entry {
        name: "yoshida4",
        options: Options::None,
        space: SpaceKind::Vector,
        summary: "Yoshida's triple jump of Störmer–Verlet: order 4, 3 stages",
    },
    Entry {
        name: "kahan-li6",
        options: Options::None,
        space: SpaceKind::Vector,
        summary: "Kahan & Li's composition of Störmer–Verlet: order 6, 9 stages",
    },
    Entry {
        name: "kahan-li8",
        options: Options::None,
        space: SpaceKind::Vector,
        summary: "Kahan & Li's composition of Störmer–Verlet: order 8, 17 stages",
    },
    Entry {
        name: "trapezoid",
        options: Options::None,
        space: SpaceKind::Vector,
        summary: "trapezoidal discrete Lagrangian, always implicit",
    },
    Entry {
        name: "symplectic-euler-h",
        options: Options::None,
        space: SpaceKind::Vector,
        summary: "symplectic Euler on Hamilton's equations, p_k+1 = p_k − h H_q(q_k, p_k+1): \
                  order 1, explicit for separable H",
    },
    Entry {
        name: "symplectic-euler-adjoint-h",
        options: Options::None,
        space: SpaceKind::Vector,
        summary: "adjoint symplectic Euler on Hamilton's equations, q_k+1 = q_k + h H_p(q_k+1, \
                  p_k): order 1, explicit for separable H",
    },
    Entry {
        name: "midpoint-h",
        options: Options::None,
        space: SpaceKind::Vector,
        summary: "implicit midpoint rule on Hamilton's equations: order 2",
    },
    Entry {
        name: "verlet-h",
        options: Options::None,
        space: SpaceKind::Vector,
        summary: "Störmer–Verlet on Hamilton's equations: order 2, explicit for separable H with \
                  any kinetic energy T(p)",
    },
    Entry {
        name: "yoshida4-h",
        options: Options::None,
        space: SpaceKind::Vector,
        summary: "Yoshida's triple jump of verlet-h: order 4, 3 stages",
    },
    Entry {
        name: "kahan-li6-h",
        options: Options::None,
        space: SpaceKind::Vector,
        summary: "Kahan & Li's composition of verlet-h: order 6, 9 stages",
    },
    Entry {
        name: "kahan-li8-h",
        options: Options::None,
        space: SpaceKind::Vector,
        summary: "Kahan & Li's composition of verlet-h: order 8, 17 stages",
    },
    Entry {
        name: "explicit-euler",
        options: Options::None,
        space: SpaceKind::Vector,
        summary: "explicit Euler on the Euler–Lagrange equations: a non-symplectic reference",
    },
    Entry {
        name: "implicit-euler",
        options: Options::None,
        space: SpaceKind::Vector,
        summary: "implicit Euler on the Euler–Lagrange equations (Newton): a non-symplectic \
                  reference",
    },
    Entry {
        name: "rk4",
        options: Options::None,
        space: SpaceKind::Vector,
        summary: "classical Runge–Kutta of order 4 on the Euler–Lagrange equations: a \
                  non-symplectic reference",
    },
    Entry {
        name: "multiscale",
        options: Options::Points {
            default: || Multiscale::default().points,
        },
        space: SpaceKind::Vector,
        summary: "multiscale variational integrator: polynomials of CGL points P plus sin ωt and \
                  cos ωt with linear envelopes, Filon–Lobatto action, ω from the linearisation; \
                  for steps of several fast periods",
    },
    Entry {
        name: "lie-svi",
        options: Options::PointsAndQuadrature {
            default_points: || LieSvi::default().points,
            default_quadrature: |points| LieSvi::new(points).quadrature_points(),
        },
        space: SpaceKind::Group,
        summary: "Lie-group spectral variational integrator on SO(3): CGL points P, Gauss points \
                  M (default P)",
    },
    Entry {
        name: "lie-svi-reduced",
        options: Options::PointsAndQuadrature {
            default_points: || LieSvi::default().points,
            default_quadrature: |points| LieSvi::new(points).quadrature_points(),
        },
        space: SpaceKind::Group,
        summary: "lie-svi in the reduced Euler–Poincaré form, for G-invariant rigid bodies: CGL \
                  points P, Gauss points M (default P)",
    },
];

/// The entry named `name`, if there is one.
pub fn find(name: &str) -> Option<&'static Entry> {
    METHODS.iter().find(|entry| entry.name == name)
}

/// The names of [`METHODS`], comma-separated.
pub fn known_names() -> String {
    METHODS
        .iter()
        .map(|entry| entry.name)
        .collect::<Vec<_>>()
        .join(", ")
}

/// The names of the methods of [`METHODS`] on Hamilton's equations ([`Equations::Hamilton`]),
/// comma-separated: those that run a model given as the right-hand side of Hamilton's
/// equations ([`crate::model::rhs::HamiltonianRhs`]).
pub fn hamiltonian_names() -> String {
    METHODS
        .iter()
        .filter(|entry| {
            entry
                .spec()
                .info()
                .is_ok_and(|info| info.equations == Equations::Hamilton)
        })
        .map(|entry| entry.name)
        .collect::<Vec<_>>()
        .join(", ")
}

/// The grammar and the methods as plain text, one method per line (`name[:P[/M]]`, summary,
/// defaults): the help text of every option that takes a method.
pub fn grammar_help() -> String {
    let width = METHODS
        .iter()
        .map(|entry| entry.grammar().len())
        .max()
        .unwrap_or(0)
        + 2;
    let mut text = String::from(
        "NAME, NAME:P or NAME:P/M, with P Chebyshev–Gauss–Lobatto points and M Gauss–Legendre \
         points for the methods that take them; omitted numbers take the defaults shown:",
    );
    for entry in METHODS {
        text.push_str(&format!("\n  {:<width$}{}", entry.grammar(), entry.summary));
        if entry.takes_points() {
            text.push_str(&format!("; {} = {}", entry.name, entry.spec().canonical()));
        }
    }
    text
}

impl Entry {
    /// Whether the name takes a number of CGL points (`name:P`).
    pub fn takes_points(&self) -> bool {
        !matches!(self.options, Options::None)
    }

    /// Whether the name takes a number of Gauss points (`name:P/M`).
    pub fn takes_quadrature(&self) -> bool {
        matches!(self.options, Options::PointsAndQuadrature { .. })
    }

    /// The number of CGL points when `name:P` omits it (`None` for methods without).
    pub fn default_points(&self) -> Option<usize> {
        match self.options {
            Options::None => None,
            Options::Points { default } => Some(default()),
            Options::PointsAndQuadrature { default_points, .. } => Some(default_points()),
        }
    }

    /// The number of Gauss points for `points` CGL points when `name:P/M` omits M (`None`
    /// for methods without a quadrature).
    pub fn default_quadrature(&self, points: usize) -> Option<usize> {
        match self.options {
            Options::PointsAndQuadrature {
                default_quadrature, ..
            } => Some(default_quadrature(points)),
            _ => None,
        }
    }

    /// The grammar of the name: `svi[:P[/M]]`, `sc[:P]`, `midpoint`.
    pub fn grammar(&self) -> String {
        match self.options {
            Options::None => self.name.to_string(),
            Options::Points { .. } => format!("{}[:P]", self.name),
            Options::PointsAndQuadrature { .. } => format!("{}[:P[/M]]", self.name),
        }
    }

    /// This method with its default options.
    pub fn spec(&'static self) -> MethodSpec {
        MethodSpec {
            entry: self,
            points: None,
            quadrature: None,
        }
    }
}

/// A method of [`METHODS`] and its options, as written `name`, `name:P` or `name:P/M` (see
/// the module documentation). Omitted options take the method's defaults.
#[derive(Debug, Clone, Copy)]
pub struct MethodSpec {
    entry: &'static Entry,
    points: Option<usize>,
    quadrature: Option<usize>,
}

impl PartialEq for MethodSpec {
    fn eq(&self, other: &Self) -> bool {
        self.entry.name == other.entry.name
            && self.points == other.points
            && self.quadrature == other.quadrature
    }
}

impl Eq for MethodSpec {}

impl Default for MethodSpec {
    /// `svi` with its default options.
    fn default() -> Self {
        METHODS[0].spec()
    }
}

/// Reads the [`MethodInfo`] of the visited method.
struct InfoOf;

impl VectorMethodVisitor<U1> for InfoOf {
    type Output = MethodInfo;
    fn visit<M: Method<U1> + Clone>(self, method: M) -> MethodInfo {
        method.info()
    }
}

/// The reason of an invalid-parameter error (for quoting it under the name `method`).
fn reason(error: Error) -> String {
    match error {
        Error::InvalidParameter { reason, .. } => reason,
        other => other.to_string(),
    }
}

impl MethodSpec {
    /// The method's name.
    pub fn name(&self) -> &'static str {
        self.entry.name
    }

    /// The method's registry entry.
    pub fn entry(&self) -> &'static Entry {
        self.entry
    }

    /// The space the method integrates on.
    pub fn space(&self) -> SpaceKind {
        self.entry.space
    }

    /// The number of CGL points as written (`None`: omitted, or a method without).
    pub fn points(&self) -> Option<usize> {
        self.points
    }

    /// The number of Gauss points as written (`None`: omitted, or a method without).
    pub fn quadrature(&self) -> Option<usize> {
        self.quadrature
    }

    /// The number of CGL points the method uses: as written, else the default (`None` for
    /// methods without).
    pub fn points_in_use(&self) -> Option<usize> {
        self.points.or_else(|| self.entry.default_points())
    }

    /// The number of Gauss points the method uses: as written, else the default for
    /// [`MethodSpec::points_in_use`] (`None` for methods without a quadrature).
    pub fn quadrature_in_use(&self) -> Option<usize> {
        self.quadrature.or_else(|| {
            self.entry
                .default_quadrature(self.points_in_use().unwrap_or_default())
        })
    }

    /// The same method with `points` CGL points (the `--points` of the command line). An
    /// error names `points` if the method takes none or the number is out of range.
    pub fn with_points(self, points: usize) -> Result<Self, Error> {
        if !self.entry.takes_points() {
            return Err(Error::invalid(
                "points",
                format!("{} takes no CGL points", self.entry.name),
            ));
        }
        check_points(points)?;
        if let Some(m) = self.quadrature {
            check_quadrature(points, m)?;
        }
        Ok(MethodSpec {
            points: Some(points),
            ..self
        })
    }

    /// The same method with `quadrature` Gauss points (the `--quadrature` of the command
    /// line); omitted CGL points become explicit defaults, as `name:P/M` needs a P. An error
    /// names `quadrature` if the method takes none or the number is out of range.
    pub fn with_quadrature(self, quadrature: usize) -> Result<Self, Error> {
        if !self.entry.takes_quadrature() {
            return Err(Error::invalid(
                "quadrature",
                format!("{} takes no Gauss points", self.entry.name),
            ));
        }
        let points = self.points_in_use().unwrap_or_default();
        check_quadrature(points, quadrature)?;
        Ok(MethodSpec {
            points: Some(points),
            quadrature: Some(quadrature),
            ..self
        })
    }

    /// The spec with every option written out: `svi:6/12`, `sc:6`, `midpoint`.
    pub fn canonical(&self) -> MethodSpec {
        MethodSpec {
            entry: self.entry,
            points: self.points_in_use(),
            quadrature: self.quadrature_in_use(),
        }
    }

    /// `Ok` if the method integrates on `space`; else an error naming the method and the
    /// methods that do.
    pub fn check_space(&self, space: SpaceKind) -> Result<(), Error> {
        if self.entry.space == space {
            return Ok(());
        }
        let (what, instead, other) = match self.entry.space {
            SpaceKind::Vector => ("models on ℝᴺ", "models on Lie groups", SpaceKind::Group),
            SpaceKind::Group => ("models on Lie groups", "models on ℝᴺ", SpaceKind::Vector),
        };
        let names: Vec<&str> = METHODS
            .iter()
            .filter(|entry| entry.space == other)
            .map(|entry| entry.name)
            .collect();
        Err(Error::invalid(
            "method",
            format!(
                "'{self}' integrates {what}, not {instead} (methods for {instead}: {})",
                names.join(", ")
            ),
        ))
    }

    /// Build the method for models on ℝᴺ: the one place where a method name becomes a
    /// method. An error names the method if it integrates rigid bodies.
    pub fn vector_method(&self) -> Result<AnyMethod, Error> {
        if let Some(scheme) = Scheme::named(self.entry.name) {
            return Ok(Composition::new(scheme).into());
        }
        if let Some(scheme) = self.entry.name.strip_suffix("-h").and_then(Scheme::named) {
            return Ok(Composition::hamiltonian(scheme).into());
        }
        let points = self.points_in_use().unwrap_or_default();
        Ok(match self.entry.name {
            "svi" | "svi-newton" => {
                let mut svi = Svi::new(points);
                if let Some(quadrature) = self.quadrature {
                    svi = svi.with_quadrature(quadrature);
                }
                if self.entry.name == "svi-newton" {
                    svi = svi.with_solver(Solver::Newton);
                }
                svi.into()
            }
            "svi-h" => {
                let galerkin = HamiltonianGalerkin::new(points);
                match self.quadrature {
                    Some(quadrature) => galerkin.with_quadrature(quadrature),
                    None => galerkin,
                }
                .into()
            }
            "sc" => SpectralCollocation::new(points).into(),
            "sc-h" => HamiltonianCollocation::new(points).into(),
            "symplectic-euler" => VariationalIntegrator::new(SymplecticEuler).into(),
            "symplectic-euler-adjoint" => VariationalIntegrator::new(AdjointSymplecticEuler).into(),
            "midpoint" => VariationalIntegrator::new(Midpoint).into(),
            "verlet" => StormerVerlet::default().into(),
            "trapezoid" => VariationalIntegrator::new(Trapezoid).into(),
            "symplectic-euler-h" => Partitioned::symplectic_euler().into(),
            "symplectic-euler-adjoint-h" => Partitioned::adjoint_symplectic_euler().into(),
            "midpoint-h" => ImplicitMidpoint::default().into(),
            "verlet-h" => Partitioned::stormer_verlet().into(),
            "multiscale" => Multiscale::new(points).into(),
            "explicit-euler" => ExplicitEuler.into(),
            "implicit-euler" => ImplicitEuler::default().into(),
            "rk4" => RungeKutta4.into(),
            _ => {
                self.check_space(SpaceKind::Vector)?;
                return Err(Error::invalid(
                    "method",
                    format!("'{self}' has no dispatch arm for models on ℝᴺ"),
                ));
            }
        })
    }

    /// Build the method for models on ℝᴺ ([`MethodSpec::vector_method`]) and hand it to
    /// `visitor` as its own type.
    pub fn visit_vector<V: VectorMethodVisitor<N>, N: Dimension>(
        &self,
        visitor: V,
    ) -> Result<V::Output, Error>
    where
        DefaultAllocator: Allocator<N> + Allocator<N, N>,
    {
        Ok(self.vector_method()?.visit(visitor))
    }

    /// Build the rigid-body method on SO(3). An error names the method if it integrates
    /// models on ℝᴺ.
    pub fn lie_svi(&self) -> Result<LieSvi, Error> {
        let form = match self.entry.name {
            "lie-svi" => Form::Full,
            "lie-svi-reduced" => Form::Reduced,
            _ => {
                self.check_space(SpaceKind::Group)?;
                return Err(Error::invalid(
                    "method",
                    format!("'{self}' has no dispatch arm for rigid bodies"),
                ));
            }
        };
        let mut method = LieSvi::new(self.points_in_use().unwrap_or_default()).with_form(form);
        if let Some(quadrature) = self.quadrature {
            method = method.with_quadrature(quadrature);
        }
        Ok(method)
    }

    /// The built method's name, order and geometric properties (methods on ℝᴺ are built at
    /// N = 1; their properties do not depend on N).
    pub fn info(&self) -> Result<MethodInfo, Error> {
        match self.entry.space {
            SpaceKind::Vector => self.visit_vector(InfoOf),
            SpaceKind::Group => Ok(self.lie_svi()?.info()),
        }
    }
}

impl fmt::Display for MethodSpec {
    /// `name`, `name:P` or `name:P/M`, as parsed.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.entry.name)?;
        if let Some(points) = self.points {
            write!(f, ":{points}")?;
            if let Some(quadrature) = self.quadrature {
                write!(f, "/{quadrature}")?;
            }
        }
        Ok(())
    }
}

impl FromStr for MethodSpec {
    type Err = Error;

    /// Parse `name`, `name:P` or `name:P/M` (surrounding white space ignored). Every error is
    /// [`Error::InvalidParameter`] named `method`, quoting the text.
    fn from_str(text: &str) -> Result<Self, Error> {
        let text = text.trim();
        let bad = |reason: String| Error::invalid("method", format!("'{text}': {reason}"));
        let (name, options) = match text.split_once(':') {
            Some((name, options)) => (name, Some(options)),
            None => (text, None),
        };
        let Some(entry) = find(name) else {
            return Err(Error::invalid(
                "method",
                format!("unknown method '{text}' (known: {})", known_names()),
            ));
        };
        let Some(options) = options else {
            return Ok(entry.spec());
        };
        let usage = || {
            format!(
                "write {}{}",
                entry.grammar(),
                if entry.takes_points() {
                    ", P CGL points"
                } else {
                    ""
                }
            ) + if entry.takes_quadrature() {
                ", M Gauss points"
            } else {
                ""
            }
        };
        if !entry.takes_points() {
            return Err(bad(format!("{name} takes no options ({})", usage())));
        }
        let (points, quadrature) = match options.split_once('/') {
            Some(_) if !entry.takes_quadrature() => {
                return Err(bad(format!(
                    "{name} takes CGL points only, no Gauss points ({})",
                    usage()
                )));
            }
            Some((points, quadrature)) => (points, Some(quadrature)),
            None => (options, None),
        };
        let number = |digits: &str, what: &str| -> Result<usize, Error> {
            if digits.is_empty() {
                return Err(bad(format!(
                    "the number of {what} is missing ({})",
                    usage()
                )));
            }
            if !digits.bytes().all(|byte| byte.is_ascii_digit()) {
                return Err(bad(format!(
                    "'{digits}' is not a number of {what} ({})",
                    usage()
                )));
            }
            // Only digits: the parse fails on overflow alone.
            digits
                .parse::<usize>()
                .map_err(|_| bad(format!("{digits} {what} is too many")))
        };
        let points = number(points, "CGL points")?;
        check_points(points).map_err(|error| bad(reason(error)))?;
        let quadrature = quadrature
            .map(|digits| number(digits, "Gauss points"))
            .transpose()?;
        if let Some(m) = quadrature {
            check_quadrature(points, m).map_err(|error| bad(reason(error)))?;
        }
        Ok(MethodSpec {
            entry,
            points: Some(points),
            quadrature,
        })
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_methods_on_hamiltons_equations_are_the_names_ending_in_h() {
        // The refusal of a right-hand side by the other methods (method/step.rs) names them so.
        let names = super::hamiltonian_names();
        for entry in METHODS
            .iter()
            .filter(|entry| entry.space == SpaceKind::Vector)
        {
            assert_eq!(
                names.split(", ").any(|name| name == entry.name),
                entry.name.ends_with("-h"),
                "{}",
                entry.name
            );
        }
        assert!(names.starts_with("svi-h, "), "{names}");
    }

    use super::*;
    use crate::dimension::{Dyn, dimension_of};
    use crate::lie_group::RigidBodyLagrangian;
    use crate::method::State;
    use crate::model::Lagrangian;
    use crate::scalar::Scalar;
    use crate::spectral::MAX_POINTS;
    use crate::test_models::{AsDyn, HenonHeiles, VariableMass};
    use nalgebra::{Matrix3, OVector, SVector, U2, Vector3};

    /// A tiny model on ℝ²: two uncoupled oscillators.
    struct Oscillators;
    impl Lagrangian<U2> for Oscillators {
        const TIME_DEPENDENT: bool = false;
        fn lagrangian<D: Scalar>(&self, _t: D, q: &SVector<D, 2>, v: &SVector<D, 2>) -> D {
            (v.dot(v) - q.dot(q)) * 0.5
        }
    }

    /// Hénon–Heiles with a constant mass (the explicit and fixed-point paths) and a force
    /// f_L = (−0.2 q̇₀, 0.1 cos t − 0.3 q₀ q̇₁).
    struct Pushed;
    impl Lagrangian<U2> for Pushed {
        const STRUCTURE: crate::model::Structure = crate::model::Structure::ConstantMass;
        const FORCED: bool = true;
        fn lagrangian<D: Scalar>(&self, t: D, q: &SVector<D, 2>, v: &SVector<D, 2>) -> D {
            HenonHeiles::<true>.lagrangian(t, q, v)
        }
        fn external_force<D: Scalar>(
            &self,
            t: D,
            q: &SVector<D, 2>,
            v: &SVector<D, 2>,
        ) -> SVector<D, 2> {
            SVector::from([v[0] * (-0.2), t.cos() * 0.1 - q[0] * v[1] * 0.3])
        }
    }

    fn spec(text: &str) -> MethodSpec {
        text.parse()
            .unwrap_or_else(|error| panic!("{text}: {error}"))
    }

    /// Every name with every option form it takes.
    fn spellings() -> Vec<String> {
        let mut texts = Vec::new();
        for entry in METHODS {
            texts.push(entry.name.to_string());
            if entry.takes_points() {
                texts.push(format!("{}:4", entry.name));
            }
            if entry.takes_quadrature() {
                texts.push(format!("{}:4/3", entry.name));
            }
        }
        texts
    }

    #[test]
    fn every_spelling_parses_and_prints_back() {
        for text in spellings() {
            let parsed = spec(&text);
            assert_eq!(parsed.to_string(), text);
            assert_eq!(spec(&parsed.to_string()), parsed);
        }
        for text in ["svi:7/6", "svi:6", "sc:9", "midpoint", "lie-svi-reduced:3"] {
            assert_eq!(spec(text).to_string(), text);
        }
        assert_eq!(spec(" svi:7/6 "), spec("svi:7/6"));
        assert_eq!(MethodSpec::default(), spec("svi"));
    }

    #[test]
    fn omitted_options_take_the_method_types_defaults() {
        let svi = spec("svi");
        assert_eq!((svi.points(), svi.quadrature()), (None, None));
        assert_eq!(svi.points_in_use(), Some(Svi::default().points));
        assert_eq!(
            svi.quadrature_in_use(),
            Some(Svi::default().quadrature_points())
        );
        assert_eq!(spec("svi:7").quadrature_in_use(), Some(14));
        assert_eq!(
            spec("sc").points_in_use(),
            Some(SpectralCollocation::default().points)
        );
        assert_eq!(spec("sc").quadrature_in_use(), None);
        assert_eq!(spec("lie-svi:4").quadrature_in_use(), Some(4));
        assert_eq!(
            spec("lie-svi").lie_svi().unwrap(),
            LieSvi::default(),
            "lie-svi is LieSvi::default()"
        );
        assert_eq!(spec("midpoint").points_in_use(), None);
        assert_eq!(spec("svi").canonical().to_string(), "svi:6/12");
        assert_eq!(spec("verlet").canonical().to_string(), "verlet");
    }

    #[test]
    fn bad_spellings_are_typed_errors_naming_the_text() {
        for bad in [
            "",
            "dopri5",
            "svi:",
            "svi:x",
            "svi:6/",
            "svi:/6",
            "svi:6/x",
            "svi:-6",
            "svi:+6",
            "svi: 6",
            "svi:0",
            "svi:1",
            "svi:257",
            "svi:6/0",
            "svi:6/257",
            "sc:",
            "sc:9/4",
            "midpoint:3",
            "verlet:",
            "svi:6:7",
            "svi:6/7/8",
            "SVI",
            "lie-svi:1",
            "svi:1e3",
            "svi:99999999999999999999999999",
        ] {
            let error = bad.parse::<MethodSpec>().unwrap_err();
            let Error::InvalidParameter { name, reason } = &error else {
                panic!("{bad}: {error:?}")
            };
            assert_eq!(name, "method", "{bad}");
            assert!(reason.contains(&format!("'{bad}'")), "{bad}: {reason}");
        }
        let unknown = "rk45".parse::<MethodSpec>().unwrap_err().to_string();
        assert!(
            unknown.contains("known: svi, svi-newton, svi-h, sc, sc-h, symplectic-euler,"),
            "{unknown}"
        );
        let message = "midpoint:3".parse::<MethodSpec>().unwrap_err().to_string();
        assert!(message.contains("takes no options"), "{message}");
        let message = "sc:9/4".parse::<MethodSpec>().unwrap_err().to_string();
        assert!(message.contains("no Gauss points"), "{message}");
    }

    #[test]
    fn the_parsers_bounds_are_the_methods_own() {
        // Exactly the numbers the methods themselves accept parse.
        for points in [0, 1, 2, 3, MAX_POINTS, MAX_POINTS + 1] {
            let text = format!("svi:{points}/1");
            let workspace =
                Method::<U2>::workspace(&Svi::new(points).with_quadrature(1), &Oscillators, 0.1);
            assert_eq!(
                text.parse::<MethodSpec>().is_ok(),
                workspace.is_ok(),
                "{text}"
            );
            let text = format!("sc:{points}");
            let workspace =
                Method::<U2>::workspace(&SpectralCollocation::new(points), &Oscillators, 0.1);
            assert_eq!(
                text.parse::<MethodSpec>().is_ok(),
                workspace.is_ok(),
                "{text}"
            );
        }
        for quadrature in [0, 1, MAX_POINTS, MAX_POINTS + 1] {
            let text = format!("svi:2/{quadrature}");
            let workspace = Method::<U2>::workspace(
                &Svi::new(2).with_quadrature(quadrature),
                &Oscillators,
                0.1,
            );
            assert_eq!(
                text.parse::<MethodSpec>().is_ok(),
                workspace.is_ok(),
                "{text}"
            );
        }
    }

    #[test]
    fn the_sugar_sets_options_and_names_the_option_it_rejects() {
        assert_eq!(spec("svi").with_points(7).unwrap(), spec("svi:7"));
        assert_eq!(
            spec("svi")
                .with_quadrature(6)
                .unwrap()
                .with_points(7)
                .unwrap(),
            spec("svi:7/6")
        );
        assert_eq!(
            spec("svi").with_quadrature(6).unwrap().to_string(),
            "svi:6/6"
        );
        assert_eq!(spec("svi:7/6").with_points(5).unwrap(), spec("svi:5/6"));
        assert_eq!(spec("sc").with_points(9).unwrap(), spec("sc:9"));
        for (result, option) in [
            (spec("midpoint").with_points(3), "points"),
            (spec("sc").with_quadrature(3), "quadrature"),
            (spec("verlet").with_quadrature(3), "quadrature"),
            (spec("svi").with_points(1), "points"),
            (spec("svi").with_quadrature(0), "quadrature"),
        ] {
            assert!(
                matches!(&result, Err(Error::InvalidParameter { name, .. }) if name == option),
                "{result:?}"
            );
        }
    }

    #[test]
    fn info_reports_the_built_methods_order() {
        let svi = spec("svi:7/6").info().unwrap();
        assert_eq!((svi.name, svi.order), ("svi", 12));
        assert!(svi.symmetric && svi.symplectic);
        let sc = spec("sc:9").info().unwrap();
        assert_eq!(
            sc.order,
            Method::<U1>::info(&SpectralCollocation::new(9)).order
        );
        assert!(!sc.symplectic);
        assert_eq!(spec("midpoint").info().unwrap().order, 2);
        assert_eq!(spec("symplectic-euler").info().unwrap().order, 1);
        assert_eq!(spec("lie-svi:3/3").info().unwrap().order, 4);
        // Every entry's built method carries the entry's name.
        for entry in METHODS {
            assert_eq!(entry.spec().info().unwrap().name, entry.name);
        }
    }

    /// Runs one step of the visited method on [`Oscillators`]: the state after it.
    struct OneStep;
    impl VectorMethodVisitor<U2> for OneStep {
        type Output = Result<crate::method::State<U2>, Error>;
        fn visit<M: Method<U2> + Clone>(self, method: M) -> Self::Output {
            // The constants that decide what is compiled for the method tell the truth.
            let name = method.info().name;
            assert!(!M::WITHOUT_POINTS || method.points().is_none(), "{name}");
            assert!(
                M::COMPOSES_VERLET || method.verlet_fractions().is_none(),
                "{name}"
            );
            // The multiscale method needs steps of about a fast period or more (ω = 1 here).
            let h = if method.info().name == "multiscale" {
                7.0
            } else {
                0.1
            };
            crate::stepping::run::Integrator::new(Oscillators, method)
                .run_from_velocity(
                    0.0,
                    SVector::from([1.0, 0.0]),
                    SVector::from([0.0, 1.0]),
                    h,
                    h,
                    &mut (),
                )
                .map(|run| run.state)
        }
    }

    /// A free rigid body with unit inertia, for one step of the rotation methods.
    struct Sphere;
    impl RigidBodyLagrangian for Sphere {
        const G_INVARIANT: bool = true;
        fn lagrangian<D: Scalar>(&self, _r: &Matrix3<D>, omega: &Vector3<D>) -> D {
            omega.dot(omega) * 0.5
        }
    }

    #[test]
    fn every_entry_dispatches_on_its_space_only() {
        for entry in METHODS {
            let spec = entry.spec();
            match entry.space {
                SpaceKind::Vector => {
                    let own = spec
                        .visit_vector(OneStep)
                        .unwrap_or_else(|error| panic!("{}: {error}", entry.name))
                        .unwrap_or_else(|error| panic!("{}: {error}", entry.name));
                    // The method as an `AnyMethod` takes the very same step.
                    let any = OneStep
                        .visit(spec.vector_method().unwrap())
                        .unwrap_or_else(|error| panic!("{}: {error}", entry.name));
                    assert_eq!(any, own, "{}", entry.name);
                    let error = spec.lie_svi().unwrap_err().to_string();
                    assert!(error.contains(entry.name), "{error}");
                }
                SpaceKind::Group => {
                    let method = spec.lie_svi().unwrap();
                    crate::lie_group::RigidBodyIntegrator::new(Sphere, method)
                        .run(
                            0.0,
                            crate::lie_group::RigidInitial::Velocity {
                                r: Matrix3::identity(),
                                omega: SVector::from([1.0, 0.5, -0.4]),
                            },
                            0.1,
                            0.1,
                            &mut (),
                        )
                        .unwrap_or_else(|error| panic!("{}: {error}", entry.name));
                    let error = spec.visit_vector(OneStep).unwrap_err().to_string();
                    assert!(error.contains(entry.name), "{error}");
                }
            }
        }
        assert_eq!(
            spec("lie-svi-reduced:3").lie_svi().unwrap().form,
            Form::Reduced
        );
        assert_eq!(spec("lie-svi:3/2").lie_svi().unwrap().quadrature, Some(2));
    }

    /// Four steps of the visited method from (q, y), then the tangent map of a fifth, on a
    /// model of fixed or run-time size: the end state, the fifth increment and the tangent
    /// map's entries, or the error that stopped it.
    struct Trace<L> {
        model: L,
        q: [f64; 2],
        y: [f64; 2],
    }

    impl<L: Lagrangian<N>, N: Dimension> VectorMethodVisitor<N> for Trace<L>
    where
        DefaultAllocator: Allocator<N> + Allocator<N, N>,
    {
        type Output = Result<Vec<f64>, String>;
        fn visit<M: Method<N> + Clone>(self, method: M) -> Result<Vec<f64>, String> {
            // The multiscale method needs steps of a fast period or more.
            let h = if method.info().name == "multiscale" {
                7.0
            } else {
                0.1
            };
            let n: N = dimension_of(self.model.dimension())?;
            let start = State {
                q: OVector::from_column_slice_generic(n, U1, &self.q),
                y: OVector::from_column_slice_generic(n, U1, &self.y),
            };
            let mut workspace = method
                .workspace(&self.model, h)
                .map_err(|error| error.to_string())?;
            let (mut state, mut increment) = (start.clone(), State::zeros(n));
            for k in 0..4 {
                method
                    .step(
                        &self.model,
                        &mut workspace,
                        k as f64 * h,
                        h,
                        &state,
                        &mut increment,
                    )
                    .map_err(|failure| format!("{failure:?}"))?;
                state.q += &increment.q;
                state.y += &increment.y;
            }
            let (fifth, tangent, _) = method
                .tangent_map(&self.model, &mut workspace, 4.0 * h, h, &state)
                .map_err(|failure| format!("{failure:?}"))?;
            Ok([&state.q, &state.y, &fifth.q, &fifth.y]
                .into_iter()
                .flat_map(|x| x.iter().copied())
                .chain(tangent.matrix().iter().copied())
                .collect())
        }
    }

    /// Every method of ℝᴺ takes the same steps, to round-off, on a model of run-time size
    /// ([`Dyn`]: scalar dual sweeps, heap vectors) as on the same model of fixed size, on each
    /// of its paths: a general Lagrangian, a constant mass matrix (explicit Störmer–Verlet,
    /// the fixed-point iterations of svi and sc) and an external force.
    #[test]
    fn every_vector_method_steps_alike_at_fixed_and_run_time_size() {
        fn compare<L: Lagrangian<U2>>(entry: &'static Entry, model: fn() -> L, must_run: bool) {
            let spec = entry.spec();
            let (q, y) = ([0.3, -0.2], [0.1, 0.4]);
            // As `AnyMethod`: the stepping loop compiled once per model, not per method.
            let method = spec.vector_method().unwrap();
            let fixed = VectorMethodVisitor::<U2>::visit(
                Trace {
                    model: model(),
                    q,
                    y,
                },
                method.clone(),
            );
            let run_time = VectorMethodVisitor::<Dyn>::visit(
                Trace {
                    model: AsDyn::<_, U2>::new(model()),
                    q,
                    y,
                },
                method,
            );
            match (fixed, run_time) {
                (Ok(a), Ok(b)) => {
                    assert_eq!(a.len(), b.len(), "{}", entry.name);
                    for (x, z) in a.iter().zip(&b) {
                        assert!(
                            (x - z).abs() <= 1e-12 * x.abs().max(1.0),
                            "{}: {x} vs {z}\n{a:?}\n{b:?}",
                            entry.name
                        );
                    }
                }
                (Err(a), Err(b)) if !must_run => assert_eq!(a, b, "{}", entry.name),
                (a, b) => panic!("{}: {a:?} vs {b:?}", entry.name),
            }
        }
        for entry in METHODS
            .iter()
            .filter(|entry| entry.space == SpaceKind::Vector)
        {
            compare(entry, || Oscillators, true);
            compare(entry, || VariableMass, entry.name != "multiscale");
            compare(entry, || HenonHeiles::<true>, entry.name != "multiscale");
            compare(entry, || Pushed, entry.name != "multiscale");
        }
    }

    #[test]
    fn the_help_lists_every_entry_with_its_grammar_and_summary() {
        let help = grammar_help();
        for entry in METHODS {
            let line = help
                .lines()
                .find(|line| {
                    line.trim_start()
                        .starts_with(&format!("{} ", entry.grammar()))
                })
                .unwrap_or_else(|| panic!("{} missing:\n{help}", entry.name));
            assert!(line.contains(entry.summary), "{line}");
        }
        assert!(
            help.contains("svi[:P[/M]]") && help.contains("; svi = svi:6/12"),
            "{help}"
        );
        assert!(!help.contains("[`"), "{help}");
    }

    /// The order column of the method table (in the guide's chapter on the command line) for
    /// `spec`: a number, or one of the formulas in P and M the table uses.
    fn table_order(cell: &str, spec: &MethodSpec) -> Option<usize> {
        let p = spec.points_in_use().unwrap_or_default();
        let m = spec.quadrature_in_use().unwrap_or_default();
        match cell {
            "2·min(P − 1, M)" => Some(2 * (p - 1).min(m)),
            "P − 1" => Some(p - 1),
            "2·(P − 1)" => Some(2 * (p - 1)),
            _ => cell.parse().ok(),
        }
    }

    #[test]
    fn the_guides_method_table_lists_every_entry_with_its_grammar_order_and_summary() {
        let chapter = include_str!("../../docs/guide/src/command-line.md");
        let rows: Vec<Vec<&str>> = chapter
            .lines()
            .skip_while(|line| *line != "| method | grammar | order | summary |")
            .skip(2)
            .take_while(|line| line.starts_with('|'))
            .map(|line| line.trim_matches('|').split(" | ").map(str::trim).collect())
            .collect();
        assert_eq!(rows.len(), METHODS.len(), "{rows:?}");
        for entry in METHODS {
            let row = rows
                .iter()
                .find(|row| row[0] == format!("`{}`", entry.name))
                .unwrap_or_else(|| panic!("{} is not in the guide's method table", entry.name));
            assert_eq!(row.len(), 4, "{row:?}");
            assert_eq!(row[1], format!("`{}`", entry.grammar()), "{row:?}");
            assert_eq!(row[3], entry.summary, "{row:?}");
            // The order column agrees with the built methods over a range of options.
            let mut specs = vec![entry.spec()];
            for points in 2..=9 {
                if entry.takes_points() {
                    specs.push(entry.spec().with_points(points).unwrap());
                }
                // Every valid number of Gauss points (at least points − 1).
                for quadrature in points - 1..=9 {
                    if entry.takes_quadrature() {
                        let spec = entry.spec().with_points(points).unwrap();
                        specs.push(spec.with_quadrature(quadrature).unwrap());
                    }
                }
            }
            for spec in specs {
                assert_eq!(
                    table_order(row[2], &spec),
                    Some(spec.info().unwrap().order),
                    "{spec}: the guide's order {}",
                    row[2]
                );
            }
        }
    }
}
