//! N bodies under Newtonian gravity, of any number of bodies in the plane or in space: a
//! model of run-time size (`Lagrangian<Dyn>`).
//!
//! With positions qᵢ ∈ ℝᵈ (d = 2 or 3) and masses mᵢ,
//!
//! L = Σᵢ ½ mᵢ |q̇ᵢ|² + Σ_{i<j} G mᵢ mⱼ / |qᵢ − qⱼ|,
//!
//! a constant mass matrix (Störmer–Verlet is explicit, the spectral methods need no Hessian).
//! Translations and rotations leave L invariant: the total linear momentum P = Σ mᵢ q̇ᵢ and
//! angular momentum Σ mᵢ qᵢ × q̇ᵢ are the Noether momenta (d + 1 of them in the plane, d + 3 in
//! space), and the energy is conserved.
//!
//! L is a sum of local terms (`LocalLagrangian`, width 6: one term per pair of bodies, each
//! body's kinetic energy in one of its pairs), so the integrators differentiate it pair by
//! pair: ∂L/∂q costs O(pairs) sweeps of one pair each, not n sweeps of all pairs
//! (`cargo bench --bench derivatives -- run-time-size`).
//!
//! The default is the outer Solar System of Hairer, Lubich & Wanner, *Geometric Numerical
//! Integration*, §I.2.4, Table 2.2: the Sun (with the inner planets' mass added), Jupiter,
//! Saturn, Uranus, Neptune and Pluto, 18 coordinates, in astronomical units and days
//! (G = 2.95912208286e-4), initial values of 5 September 1994; h = 10 days over 200 000
//! days, as in Fig. I.2.4.

use nalgebra::{Const, DVector, SVector};
use svi::model::TermSum;
use svi::model::local::{LocalLagrangian, TermWidth};
use svi::{
    Defaults, Dyn, Error, ExactSolution, Invariants, Lagrangian, Scalar, Structure, Symmetries,
};

/// One body: a name, a mass and its initial position and velocity.
#[derive(Debug, Clone, PartialEq)]
pub struct Body {
    /// The name, which prefixes its coordinates (`jupiter_x`, …).
    pub name: String,
    /// The mass m > 0.
    pub mass: f64,
    /// Initial position (d entries).
    pub position: Vec<f64>,
    /// Initial velocity (d entries).
    pub velocity: Vec<f64>,
}

/// N bodies under Newtonian gravity (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct NBody {
    /// The gravitational constant G > 0.
    pub g: f64,
    /// d = 2 or 3.
    space: usize,
    bodies: Vec<Body>,
    /// The pairs (i, j), i < j, in the order of the terms.
    pairs: Vec<(usize, usize)>,
}

/// The pairs (i, j), i < j, of `count` bodies, row by row.
fn pairs(count: usize) -> Vec<(usize, usize)> {
    (0..count)
        .flat_map(|i| (i + 1..count).map(move |j| (i, j)))
        .collect()
}

/// Names of the momenta: linear in x, y (, z), then angular.
const PLANAR_MOMENTA: [&str; 3] = ["Px", "Py", "L"];
/// Names of the momenta in space.
const SPATIAL_MOMENTA: [&str; 6] = ["Px", "Py", "Pz", "Lx", "Ly", "Lz"];

impl NBody {
    /// The model's name.
    pub const NAME: &'static str = "nbody";

    /// Its parameters.
    pub const PARAMETERS: [&'static str; 1] = ["G"];

    /// Bodies in d = `space` dimensions with the gravitational constant `g`.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for d other than 2 or 3, fewer than two bodies, a mass or
    /// G not positive and finite, or a position or velocity without d finite entries.
    pub fn new(g: f64, space: usize, bodies: Vec<Body>) -> Result<Self, Error> {
        if !(g.is_finite() && g > 0.0) {
            return Err(Error::invalid(
                "G",
                format!("{g} is not positive and finite"),
            ));
        }
        if !(space == 2 || space == 3) {
            return Err(Error::invalid(
                "space",
                format!("{space}: bodies move in 2 or 3 dimensions"),
            ));
        }
        if bodies.len() < 2 {
            return Err(Error::invalid("bodies", "at least two bodies"));
        }
        for body in &bodies {
            if !(body.mass.is_finite() && body.mass > 0.0) {
                return Err(Error::invalid(
                    "mass",
                    format!("{}: {} is not positive", body.name, body.mass),
                ));
            }
            for x in [&body.position, &body.velocity] {
                if x.len() != space || !x.iter().all(|x| x.is_finite()) {
                    return Err(Error::invalid(
                        "bodies",
                        format!("{}: {x:?} is not {space} finite numbers", body.name),
                    ));
                }
            }
        }
        Ok(NBody {
            g,
            space,
            pairs: pairs(bodies.len()),
            bodies,
        })
    }

    /// The outer Solar System of HLW, Table I.2.2 (see the module docs).
    pub fn outer_solar_system() -> Self {
        let body = |name: &str, mass: f64, position: [f64; 3], velocity: [f64; 3]| Body {
            name: name.into(),
            mass,
            position: position.to_vec(),
            velocity: velocity.to_vec(),
        };
        let bodies = vec![
            body("sun", 1.00000597682, [0.0; 3], [0.0; 3]),
            body(
                "jupiter",
                0.000954786104043,
                [-3.5023653, -3.8169847, -1.5507963],
                [0.00565429, -0.00412490, -0.00190589],
            ),
            body(
                "saturn",
                0.000285583733151,
                [9.0755314, -3.0458353, -1.6483708],
                [0.00168318, 0.00483525, 0.00192462],
            ),
            body(
                "uranus",
                0.0000437273164546,
                [8.3101420, -16.2901086, -7.2521278],
                [0.00354178, 0.00137102, 0.00055029],
            ),
            body(
                "neptune",
                0.0000517759138449,
                [11.4707666, -25.7294829, -10.8169456],
                [0.00288930, 0.00114527, 0.00039677],
            ),
            body(
                "pluto",
                1.0 / 1.3e8,
                [-15.5387357, -25.2225594, -3.1902382],
                [0.00276725, -0.00170702, -0.00136504],
            ),
        ];
        NBody {
            g: 2.95912208286e-4,
            space: 3,
            pairs: pairs(bodies.len()),
            bodies,
        }
    }

    /// The bodies.
    pub fn bodies(&self) -> &[Body] {
        &self.bodies
    }

    /// d, the dimension each body moves in.
    pub fn space(&self) -> usize {
        self.space
    }
}

impl Default for NBody {
    fn default() -> Self {
        NBody::outer_solar_system()
    }
}

impl Lagrangian<Dyn> for NBody {
    const TIME_DEPENDENT: bool = false;
    const STRUCTURE: Structure = Structure::ConstantMass;

    fn dimension(&self) -> usize {
        LocalLagrangian::dimension(self)
    }

    /// The sum of the pair terms ([`LocalLagrangian::term`]).
    #[inline]
    fn lagrangian<D: Scalar>(&self, t: D, q: &DVector<D>, v: &DVector<D>) -> D {
        (0..self.pairs.len()).fold(D::from(0.0), |sum, e| {
            sum + <Const<6> as TermWidth>::value(self, e, t, q, v)
        })
    }

    /// L as the sum of its pair terms (see the module docs).
    #[inline]
    fn terms(&self) -> Option<&dyn TermSum<Dyn>> {
        Some(self)
    }
}

/// L = Σ over pairs (i, j) of G mᵢmⱼ/|qᵢ − qⱼ|, with ½mᵢ|q̇ᵢ|² in the pair (i, i + 1) and the
/// last body's ½m|q̇|² in the last such pair: every body's kinetic energy once.
impl LocalLagrangian for NBody {
    type Width = Const<6>;
    const TIME_DEPENDENT: bool = false;
    const STRUCTURE: Structure = Structure::ConstantMass;
    /// The six directions share the pair's square root and reciprocal.
    const VECTOR_SWEEP: bool = true;

    fn dimension(&self) -> usize {
        self.bodies.len() * self.space
    }

    fn term_count(&self) -> usize {
        self.pairs.len()
    }

    /// Slots 0..d the coordinates of body i, slots 3..3 + d those of body j; in the plane the
    /// third slot of each repeats the second (and the term does not read it).
    #[inline]
    fn indices(&self, e: usize) -> [usize; 6] {
        let (i, j) = self.pairs[e];
        let d = self.space;
        std::array::from_fn(|slot| {
            let body = if slot < 3 { i } else { j };
            d * body + (slot % 3).min(d - 1)
        })
    }

    #[inline]
    fn term<D: Scalar>(&self, e: usize, _t: D, q: &SVector<D, 6>, v: &SVector<D, 6>) -> D {
        let (i, j) = self.pairs[e];
        let (a, b) = (&self.bodies[i], &self.bodies[j]);
        let d = self.space;
        let squared = |x: &SVector<D, 6>, first: usize| {
            (0..d).fold(D::from(0.0), |sum, k| sum + x[first + k] * x[first + k])
        };
        let mut r2 = D::from(0.0);
        for k in 0..d {
            let x = q[k] - q[3 + k];
            r2 += x * x;
        }
        let mut term = r2.sqrt().recip() * (self.g * a.mass * b.mass);
        if j == i + 1 {
            term += squared(v, 0) * (0.5 * a.mass);
            if j + 1 == self.bodies.len() {
                term += squared(v, 3) * (0.5 * b.mass);
            }
        }
        term
    }
}

impl Symmetries<Dyn> for NBody {
    #[inline]
    fn generator_count(&self) -> usize {
        if self.space == 2 { 3 } else { 6 }
    }

    /// `Px`, `Py` (, `Pz`): linear momentum; `L` (in the plane) or `Lx`, `Ly`, `Lz`: angular.
    ///
    /// # Panics
    /// If `index >= generator_count()`.
    fn momentum_name(&self, index: usize) -> &'static str {
        if self.space == 2 {
            PLANAR_MOMENTA[index]
        } else {
            SPATIAL_MOMENTA[index]
        }
    }

    /// Translations of every body along axis k (index k < d), and rotations of every body
    /// about the origin (in the plane (x, y) ↦ (−y, x); in space about axis index − d).
    ///
    /// # Panics
    /// If `index >= generator_count()`.
    #[inline]
    fn generator(&self, index: usize, q: &DVector<f64>) -> DVector<f64> {
        self.check_generator(index);
        DVector::from_fn(q.len(), |row, _| self.generator_entry(index, q, row))
    }

    /// p·ξᵢ(q) body by body, without the vector ξᵢ (observed at every step): the linear
    /// momenta's component along the axis, or the angular momenta's xᵢ × pᵢ about it.
    ///
    /// # Panics
    /// If `index >= generator_count()`.
    fn generator_momentum(&self, index: usize, q: &DVector<f64>, p: &DVector<f64>) -> f64 {
        self.check_generator(index);
        let d = self.space;
        let bodies = q
            .as_slice()
            .chunks_exact(d)
            .zip(p.as_slice().chunks_exact(d));
        if index < d {
            return bodies.map(|(_, p)| p[index]).sum();
        }
        let (i, j) = match self.rotation_axis(index) {
            0 => (1, 2),
            1 => (2, 0),
            _ => (0, 1),
        };
        bodies.map(|(x, p)| x[i] * p[j] - x[j] * p[i]).sum()
    }
}

impl NBody {
    /// Panics unless `index < generator_count()`.
    fn check_generator(&self, index: usize) {
        assert!(
            index < self.generator_count(),
            "no symmetry generator with index {index}"
        );
    }

    /// The axis (0, 1, 2) of rotation generator `index` (≥ d): e_z in the plane.
    fn rotation_axis(&self, index: usize) -> usize {
        if self.space == 2 {
            2
        } else {
            index - self.space
        }
    }

    /// Entry `row` of the generator ξ_index(q) (see [`Symmetries::generator`]).
    #[inline]
    fn generator_entry(&self, index: usize, q: &DVector<f64>, row: usize) -> f64 {
        let d = self.space;
        let (body, k) = (row / d, row % d);
        let x = |axis: usize| q[d * body + axis];
        if index < d {
            return f64::from(k == index);
        }
        // ω × x with ω the unit vector of the rotation axis.
        let axis = self.rotation_axis(index);
        match (axis, k) {
            (0, 1) => -x(2),
            (0, 2) => x(1),
            (1, 0) => x(2),
            (1, 2) => -x(0),
            (2, 0) => -x(1),
            (2, 1) => x(0),
            _ => 0.0,
        }
    }
}

impl Invariants<Dyn> for NBody {}

impl ExactSolution<Dyn> for NBody {
    /// None: the N-body problem has no closed form.
    fn exact_solution(
        &self,
        _t0: f64,
        _q0: &DVector<f64>,
        _v0: &DVector<f64>,
        _t: f64,
    ) -> Option<(DVector<f64>, DVector<f64>)> {
        None
    }
}

impl Defaults<Dyn> for NBody {
    fn name(&self) -> &'static str {
        Self::NAME
    }

    /// `<body>_x`, `<body>_y` (, `<body>_z`) for each body.
    fn coordinate_names(&self) -> Vec<String> {
        let axes = &["x", "y", "z"][..self.space];
        self.bodies
            .iter()
            .flat_map(|body| axes.iter().map(move |axis| format!("{}_{axis}", body.name)))
            .collect()
    }

    fn parameters(&self) -> Vec<(&'static str, f64)> {
        vec![("G", self.g)]
    }

    fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), Error> {
        match name {
            "G" if value.is_finite() && value > 0.0 => {
                self.g = value;
                Ok(())
            }
            "G" => Err(Error::invalid(
                "G",
                format!("{value} is not positive and finite"),
            )),
            _ => Err(Error::invalid(
                name,
                format!("unknown parameter (known: {})", Self::PARAMETERS.join(", ")),
            )),
        }
    }

    /// The bodies' initial positions and velocities at t = 0.
    fn initial_state(&self) -> (f64, DVector<f64>, DVector<f64>) {
        let stack = |part: fn(&Body) -> &Vec<f64>| {
            DVector::from_iterator(
                Lagrangian::dimension(self),
                self.bodies
                    .iter()
                    .flat_map(|body| part(body).iter().copied()),
            )
        };
        (
            0.0,
            stack(|body| &body.position),
            stack(|body| &body.velocity),
        )
    }

    /// h = 10 (days for the Solar System).
    fn default_step(&self) -> f64 {
        10.0
    }

    /// 200 000 (days: HLW's Fig. I.2.4).
    fn default_horizon(&self) -> f64 {
        200_000.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use svi::LagrangianExt;

    /// Two bodies in the plane: the force on each is G m₁ m₂ / r² toward the other, and each
    /// generator leaves L unchanged to first order.
    #[test]
    fn two_bodies_attract_by_the_inverse_square_law_and_keep_their_symmetries() {
        let body = |name: &str, mass: f64, x: f64| Body {
            name: name.into(),
            mass,
            position: vec![x, 0.5],
            velocity: vec![0.1 * x, -0.2],
        };
        let model = NBody::new(2.0, 2, vec![body("a", 3.0, 1.0), body("b", 5.0, -1.0)]).unwrap();
        let (_, q, v) = model.initial_state();
        let force = model.force(0.0, &q, &v);
        // r = 2 along x: |F| = G m₁ m₂ / r² = 2·3·5/4 = 7.5, body a pulled toward −x.
        let expected = [-7.5, 0.0, 7.5, 0.0];
        for (f, e) in force.iter().zip(expected) {
            assert!((f - e).abs() <= 1e-14, "{force}");
        }
        for index in 0..model.generator_count() {
            assert!(
                model.symmetry_defect(index, 0.0, &q, &v) <= 1e-12,
                "{index}"
            );
        }
        assert_momenta_are_generators(&model, &q, &v);
        assert_eq!(model.coordinate_names(), ["a_x", "a_y", "b_x", "b_y"]);
        assert!(NBody::new(2.0, 4, model.bodies().to_vec()).is_err());
        assert!(NBody::new(-2.0, 2, model.bodies().to_vec()).is_err());
    }

    #[test]
    fn the_outer_solar_system_keeps_its_momenta_as_symmetries() {
        let model = NBody::default();
        assert_eq!(Lagrangian::dimension(&model), 18);
        let (_, q, v) = model.initial_state();
        for index in 0..6 {
            assert!(
                model.symmetry_defect(index, 0.0, &q, &v) <= 1e-10,
                "{index}"
            );
        }
        assert_momenta_are_generators(&model, &q, &v);
    }

    /// L as one function of all coordinates, for the AD of the whole (n scalar sweeps).
    struct Whole<'a>(&'a NBody);

    impl svi::dimension::PhaseFunction<Dyn> for Whole<'_> {
        fn eval<S: Scalar>(&self, t: S, q: &DVector<S>, v: &DVector<S>) -> S {
            self.0.lagrangian(t, q, v)
        }
    }

    /// The pair terms are L: their sum is L written out, and the term-by-term ∂L/∂q and ∂L/∂q̇
    /// (what the integrators take: gathered, one vector sweep per pair, scattered) are the
    /// derivatives of L as one function of all coordinates, in space (the outer Solar System, 15 pairs) and in the plane (three
    /// bodies, where each pair's third slots are padding).
    #[test]
    fn the_pair_terms_are_the_lagrangian() {
        use svi::dimension::{Wrt, scalar_gradient};
        let planar = NBody::new(
            1.5,
            2,
            [
                (1.0, [0.0, 0.1], [0.2, 0.0]),
                (0.5, [1.0, -0.3], [0.0, 0.7]),
                (0.25, [-0.4, 0.9], [-0.3, -0.1]),
            ]
            .iter()
            .enumerate()
            .map(|(k, &(mass, position, velocity))| Body {
                name: format!("b{k}"),
                mass,
                position: position.to_vec(),
                velocity: velocity.to_vec(),
            })
            .collect(),
        )
        .unwrap();
        for model in [NBody::outer_solar_system(), planar] {
            let (_, q, v) = model.initial_state();
            // L written out: Σ ½ mᵢ|q̇ᵢ|² + Σ_{i<j} G mᵢmⱼ/|qᵢ − qⱼ|.
            let d = model.space();
            let body = |x: &DVector<f64>, i: usize| x.rows(d * i, d).into_owned();
            let bodies = model.bodies();
            let mut written = 0.0;
            for (i, a) in bodies.iter().enumerate() {
                written += 0.5 * a.mass * body(&v, i).norm_squared();
                for (j, b) in bodies.iter().enumerate().skip(i + 1) {
                    written += model.g * a.mass * b.mass / (body(&q, i) - body(&q, j)).norm();
                }
            }
            for value in [
                model.lagrangian(0.0, &q, &v),
                TermSum::value(&model, 0.0, &q, &v),
            ] {
                assert!(
                    (value - written).abs() <= 1e-14 * written.abs(),
                    "{value} against {written}"
                );
            }
            for (wrt, by_terms) in [
                (Wrt::Position, model.force(0.0, &q, &v)),
                (Wrt::Velocity, model.momentum(0.0, &q, &v)),
            ] {
                let (_, by_whole) = scalar_gradient(&Whole(&model), 0.0, &q, &v, wrt);
                let gap = (&by_terms - &by_whole).amax();
                assert!(gap <= 1e-14 * by_whole.amax(), "{wrt:?}: {gap:e}");
            }
        }
    }

    /// The momenta the observer takes, p·ξᵢ(q) without the vector ξᵢ, are those of the
    /// generators, at p = M q̇ (masses on the diagonal).
    fn assert_momenta_are_generators(model: &NBody, q: &DVector<f64>, v: &DVector<f64>) {
        let p = model.momentum(0.0, q, v);
        for index in 0..model.generator_count() {
            let by_vector = p.dot(&model.generator(index, q));
            let entrywise = model.generator_momentum(index, q, &p);
            assert!(
                (entrywise - by_vector).abs() <= 1e-15 * (1.0 + by_vector.abs()),
                "{index}: {entrywise} against {by_vector}"
            );
        }
    }
}
