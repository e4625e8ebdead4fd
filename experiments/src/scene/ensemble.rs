//! The members of an ensemble (`svi ensemble`): which scene fields vary and over which values.
//!
//! An [`Axis`] names what varies — a model parameter (`--param e=0.1:0.9:81`) or one
//! component of the initial state (`--initial q.alpha1=-3:3:200`) — and its [`Values`]: a grid
//! `LO:HI:COUNT` (inclusive, evenly spaced as NumPy's `linspace`), a list `V1,V2,...` (whose
//! items may be grids: `0:0.9:999,1.2`), or for
//! random draws a range `LO:HI`. Several axes make the Cartesian product of their values, the
//! first axis slowest ([`members`]); with [`Random`] each member draws every axis uniformly
//! from its range (or its list) with a seeded Xoshiro256++ generator, so a seed gives the same
//! members on every machine and thread count.
//!
//! A [`Member`] is applied to a copy of the ensemble's scene ([`Member::apply`]) through the
//! same overrides as `svi run --param` and the scene's `[initial]` fields: a member's run is
//! exactly `svi run` of that scene.

use nalgebra::DefaultAllocator;
use nalgebra::allocator::Allocator;
use std::fmt;
use svi::Dimension;

use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};
use svi::method::registry::SpaceKind;
use svi_models::{
    GroupModelVisitor, GroupZooModel, LocalModelVisitor, LocalZooModel, ModelVisitor,
    RigidModelVisitor, RigidZooModel, ZooModel,
};

use crate::report::csv::Float;
use crate::scene::error::SceneError;
use crate::scene::overrides::Overrides;
use crate::scene::schema::Components;
use crate::scene::{Scene, Text};

/// The largest number of members of one ensemble (each keeps its summary until the table is
/// written: about 2 kB).
pub const MAX_MEMBERS: usize = 1_000_000;

/// The values an axis takes.
#[derive(Debug, Clone, PartialEq)]
pub enum Values {
    /// `LO:HI:COUNT`: `COUNT` evenly spaced values from `LO` to `HI`, both included (as
    /// `numpy.linspace`: `LO + i·(HI − LO)/(COUNT − 1)`, the last value exactly `HI`).
    Grid {
        /// First value.
        lo: f64,
        /// Last value.
        hi: f64,
        /// Number of values (at least 1; 1 gives `LO`).
        count: usize,
    },
    /// `V1,V2,...`: these values, in this order.
    List(Vec<f64>),
    /// `LO:HI`: a range to draw from (random ensembles only).
    Range {
        /// Lower end.
        lo: f64,
        /// Upper end.
        hi: f64,
    },
}

impl Values {
    /// The grid or list values (a range has none: it is drawn from).
    pub fn points(&self) -> Option<Vec<f64>> {
        match *self {
            Values::Grid { lo, hi, count } => Some(linspace(lo, hi, count)),
            Values::List(ref values) => Some(values.clone()),
            Values::Range { .. } => None,
        }
    }

    /// How many values a grid or list has.
    fn len(&self) -> Option<usize> {
        match self {
            Values::Grid { count, .. } => Some(*count),
            Values::List(values) => Some(values.len()),
            Values::Range { .. } => None,
        }
    }

    /// One uniform draw: from `[LO, HI]` for a range or a grid, one of the values of a list.
    fn draw(&self, rng: &mut Xoshiro256PlusPlus) -> f64 {
        match *self {
            Values::Grid { lo, hi, .. } | Values::Range { lo, hi } => {
                if lo == hi {
                    lo
                } else {
                    rng.random_range(lo..=hi)
                }
            }
            Values::List(ref values) => values[rng.random_range(0..values.len())],
        }
    }
}

/// `count` evenly spaced values from `lo` to `hi`, both included, computed as NumPy's
/// `linspace` does (so a Python caller can reproduce them).
pub fn linspace(lo: f64, hi: f64, count: usize) -> Vec<f64> {
    if count == 1 {
        return vec![lo];
    }
    let step = (hi - lo) / (count - 1) as f64;
    (0..count)
        .map(|i| {
            if i + 1 == count {
                hi
            } else {
                lo + i as f64 * step
            }
        })
        .collect()
}

/// A component of the initial state: `q`, `v` or `p` (ℝᴺ scenes).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InitialField {
    /// Configuration.
    Q,
    /// Velocity.
    V,
    /// Momentum.
    P,
}

impl InitialField {
    /// `q`, `v` or `p`.
    pub fn name(self) -> &'static str {
        match self {
            InitialField::Q => "q",
            InitialField::V => "v",
            InitialField::P => "p",
        }
    }
}

/// What an axis varies.
#[derive(Debug, Clone, PartialEq)]
pub enum Target {
    /// A model parameter, by name.
    Parameter(String),
    /// One component of the initial state: a field and a coordinate, by the model's name for
    /// it (`alpha1`, as `svi list` shows) or by its 0-based index.
    Initial {
        /// `q`, `v` or `p`.
        field: InitialField,
        /// The coordinate as written.
        coordinate: String,
    },
}

/// One varied scene field and its values.
#[derive(Debug, Clone, PartialEq)]
pub struct Axis {
    /// What varies.
    pub target: Target,
    /// Over which values.
    pub values: Values,
}

impl Axis {
    /// The name of the axis, also its column in the table: the parameter's name, or
    /// `q.alpha1` for an initial component.
    pub fn name(&self) -> String {
        match &self.target {
            Target::Parameter(name) => name.clone(),
            Target::Initial { field, coordinate } => format!("{}.{coordinate}", field.name()),
        }
    }
}

impl fmt::Display for Axis {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.name())
    }
}

/// A malformed axis: the option, the text and what is wrong.
fn malformed(option: &'static str, text: &str, reason: impl fmt::Display) -> SceneError {
    SceneError::InvalidOption {
        option,
        reason: format!("'{text}': {reason}"),
    }
}

/// Parse a finite number of an axis.
fn number(option: &'static str, text: &str, item: &str) -> Result<f64, SceneError> {
    let value: f64 = item
        .trim()
        .parse()
        .map_err(|_| malformed(option, text, format!("'{}' is not a number", item.trim())))?;
    if value.is_finite() {
        Ok(value)
    } else {
        Err(malformed(
            option,
            text,
            format!("{} is not a finite number", Float(value)),
        ))
    }
}

/// Parse the values of an axis: `LO:HI:COUNT`, `LO:HI` or `V1,V2,...` (whose items may be
/// grids `LO:HI:COUNT`).
fn parse_values(option: &'static str, text: &str, spec: &str) -> Result<Values, SceneError> {
    if spec.contains(',') {
        // A list of values and grids, concatenated: `0:0.9:999,1.2`.
        let mut values = Vec::new();
        for item in spec.split(',') {
            match parse_values(option, text, item)? {
                Values::Range { .. } => {
                    return Err(malformed(
                        option,
                        text,
                        "a range LO:HI cannot be part of a list (give LO:HI:COUNT)",
                    ));
                }
                item => {
                    // Counted before the values are made: no list longer than an ensemble.
                    if item.len().unwrap_or(0) > MAX_MEMBERS - values.len() {
                        return Err(malformed(
                            option,
                            text,
                            format!(
                                "the list has more than {MAX_MEMBERS} values (the most members)"
                            ),
                        ));
                    }
                    values.extend(item.points().unwrap_or_default())
                }
            }
        }
        return Ok(Values::List(values));
    }
    let parts: Vec<&str> = spec.split(':').collect();
    match parts.as_slice() {
        [single] => Ok(Values::List(vec![number(option, text, single)?])),
        [lo, hi, rest @ ..] if rest.len() <= 1 => {
            let (lo, hi) = (number(option, text, lo)?, number(option, text, hi)?);
            if lo > hi {
                return Err(malformed(
                    option,
                    text,
                    format!("LO = {} exceeds HI = {}", Float(lo), Float(hi)),
                ));
            }
            if !(hi - lo).is_finite() {
                return Err(malformed(
                    option,
                    text,
                    "HI − LO overflows: the range is wider than the largest number",
                ));
            }
            match rest {
                [] => Ok(Values::Range { lo, hi }),
                [count] => {
                    let count: usize = count.trim().parse().map_err(|_| {
                        malformed(
                            option,
                            text,
                            format!("COUNT '{}' is not a whole number", count.trim()),
                        )
                    })?;
                    if !(1..=MAX_MEMBERS).contains(&count) {
                        return Err(malformed(
                            option,
                            text,
                            format!("COUNT is {count}; need 1 to {MAX_MEMBERS} (the most members)"),
                        ));
                    }
                    Ok(Values::Grid { lo, hi, count })
                }
                _ => unreachable!("at most one part after LO:HI"),
            }
        }
        _ => Err(malformed(
            option,
            text,
            "expected LO:HI:COUNT, LO:HI (with --random) or V1,V2,...",
        )),
    }
}

/// Split `NAME=SPEC`.
fn split_axis<'t>(option: &'static str, text: &'t str) -> Result<(&'t str, &'t str), SceneError> {
    let (name, spec) = text
        .split_once('=')
        .ok_or_else(|| malformed(option, text, "expected NAME=SPEC"))?;
    let name = name.trim();
    if name.is_empty() {
        return Err(malformed(option, text, "the name is empty"));
    }
    Ok((name, spec))
}

/// Parse the argument of `--param`: `NAME=LO:HI:COUNT`, `NAME=LO:HI` or `NAME=V1,V2,...`.
pub fn parse_parameter_axis(text: &str) -> Result<Axis, SceneError> {
    let (name, spec) = split_axis("--param", text)?;
    Ok(Axis {
        target: Target::Parameter(name.into()),
        values: parse_values("--param", text, spec)?,
    })
}

/// Parse the argument of `--initial`: `FIELD.COORDINATE=SPEC`, FIELD one of `q`, `v`, `p` and
/// COORDINATE the model's name of the coordinate (`alpha1`) or its 0-based index.
pub fn parse_initial_axis(text: &str) -> Result<Axis, SceneError> {
    let option = "--initial";
    let (name, spec) = split_axis(option, text)?;
    let (field, coordinate) = name
        .split_once('.')
        .filter(|(_, coordinate)| !coordinate.is_empty())
        .ok_or_else(|| {
            malformed(
                option,
                text,
                "expected FIELD.COORDINATE=SPEC, e.g. q.alpha1=-3:3:200 or q.0=-3:3:200",
            )
        })?;
    let field = match field {
        "q" => InitialField::Q,
        "v" => InitialField::V,
        "p" => InitialField::P,
        other => {
            return Err(malformed(
                option,
                text,
                format!("unknown field '{other}' (known: q, v, p)"),
            ));
        }
    };
    Ok(Axis {
        target: Target::Initial {
            field,
            coordinate: coordinate.into(),
        },
        values: parse_values(option, text, spec)?,
    })
}

/// Random draws instead of a grid: `count` members, every axis drawn uniformly.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Random {
    /// Members.
    pub count: usize,
    /// Seed of the Xoshiro256++ generator.
    pub seed: u64,
}

/// The members of an ensemble: the Cartesian product of the axes' values (the first axis
/// slowest), or `random.count` uniform draws. Without axes, one member: the scene itself.
pub fn members(axes: &[Axis], random: Option<Random>) -> Result<Vec<Member>, SceneError> {
    let mut names: Vec<String> = Vec::new();
    for axis in axes {
        let name = axis.name();
        if names.contains(&name) {
            return Err(SceneError::InvalidOption {
                option: option_of(axis),
                reason: format!("{name} is varied twice; give each name once"),
            });
        }
        names.push(name);
    }
    match random {
        Some(Random { count, seed }) => {
            if count == 0 || count > MAX_MEMBERS {
                return Err(SceneError::InvalidOption {
                    option: "--random",
                    reason: format!("{count} members; need 1 to {MAX_MEMBERS}"),
                });
            }
            if axes.is_empty() {
                return Err(SceneError::InvalidOption {
                    option: "--random",
                    reason: "nothing to draw: give --param or --initial ranges".into(),
                });
            }
            let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
            Ok((0..count)
                .map(|_| Member {
                    values: axes.iter().map(|axis| axis.values.draw(&mut rng)).collect(),
                })
                .collect())
        }
        None => {
            if let Some(axis) = axes
                .iter()
                .find(|axis| matches!(axis.values, Values::Range { .. }))
            {
                return Err(SceneError::InvalidOption {
                    option: option_of(axis),
                    reason: format!(
                        "{axis} gives a range LO:HI without COUNT, which only --random draws \
                         from; give LO:HI:COUNT for a grid"
                    ),
                });
            }
            let count = axes.iter().try_fold(1usize, |total, axis| {
                total
                    .checked_mul(axis.values.len().unwrap_or(1))
                    .filter(|&total| total <= MAX_MEMBERS)
            });
            let Some(count) = count else {
                return Err(SceneError::InvalidOption {
                    option: "--param/--initial",
                    reason: format!("the grid has more than {MAX_MEMBERS} members"),
                });
            };
            let points: Vec<Vec<f64>> = axes
                .iter()
                .map(|axis| axis.values.points().unwrap_or_default())
                .collect();
            Ok((0..count)
                .map(|mut index| {
                    let mut values = vec![0.0; axes.len()];
                    for (slot, axis_points) in values.iter_mut().zip(&points).rev() {
                        *slot = axis_points[index % axis_points.len()];
                        index /= axis_points.len();
                    }
                    Member { values }
                })
                .collect())
        }
    }
}

/// The option that gives an axis.
fn option_of(axis: &Axis) -> &'static str {
    match axis.target {
        Target::Parameter(_) => "--param",
        Target::Initial { .. } => "--initial",
    }
}

/// One member of an ensemble: a value for each axis, in the axes' order.
#[derive(Debug, Clone, PartialEq)]
pub struct Member {
    /// The value of each axis.
    pub values: Vec<f64>,
}

impl Member {
    /// The scene of this member: `scene` with the member's parameters applied as `svi run
    /// --param` applies them, and its initial components written into `[initial]` (the other
    /// components as the scene or the model's defaults give them, for the member's
    /// parameters). Not checked: its run checks it, once.
    pub fn apply(&self, axes: &[Axis], scene: &Scene) -> Result<Scene, SceneError> {
        let mut scene = scene.clone();
        let parameters: Vec<(String, f64)> = axes
            .iter()
            .zip(&self.values)
            .filter_map(|(axis, value)| match &axis.target {
                Target::Parameter(name) => Some((name.clone(), *value)),
                Target::Initial { .. } => None,
            })
            .collect();
        if !parameters.is_empty() {
            scene.overlay(&Overrides {
                parameters,
                ..Overrides::default()
            })?;
        }
        let initial: Vec<(InitialField, &str, f64)> = axes
            .iter()
            .zip(&self.values)
            .filter_map(|(axis, value)| match &axis.target {
                Target::Initial { field, coordinate } => {
                    Some((*field, coordinate.as_str(), *value))
                }
                Target::Parameter(_) => None,
            })
            .collect();
        if initial.is_empty() {
            return Ok(scene);
        }
        let resolve = ResolveInitial { scene: &scene };
        let resolved = match scene.text() {
            Some(text) => match text? {
                Text::Model(model) => svi_models::visit_text_model(model, resolve)??,
                Text::Chain(_) => {
                    return Err(SceneError::NotApplicable {
                        option: "--initial",
                        reason: "a chain's initial state is given site by site".into(),
                    });
                }
            },
            None => svi_models::visit_model(&scene.model, resolve)??,
        };
        let (names, mut state) = resolved;
        for (field, coordinate, value) in initial {
            let index =
                coordinate_index(&names, coordinate).ok_or_else(|| SceneError::InvalidOption {
                    option: "--initial",
                    reason: format!(
                        "model '{}' has no coordinate '{coordinate}' (coordinates: {}; or an \
                         index from 0)",
                        scene.model,
                        names.join(", ")
                    ),
                })?;
            let vector = match (field, &mut state) {
                (
                    InitialField::Q,
                    InitialVectors::Velocity { q, .. } | InitialVectors::Momentum { q, .. },
                ) => q,
                (InitialField::V, InitialVectors::Velocity { v, .. })
                | (InitialField::P, InitialVectors::Momentum { p: v, .. }) => v,
                (field, _) => {
                    let given = if field == InitialField::V { "p" } else { "v" };
                    return Err(SceneError::InvalidOption {
                        option: "--initial",
                        reason: format!(
                            "the scene's initial state gives {given}, not {}: vary {given}",
                            field.name()
                        ),
                    });
                }
            };
            vector[index] = value;
        }
        match state {
            InitialVectors::Velocity { q, v } => {
                scene.initial.q = Some(Components::Values(q));
                scene.initial.v = Some(Components::Values(v));
            }
            InitialVectors::Momentum { q, p } => {
                scene.initial.q = Some(Components::Values(q));
                scene.initial.p = Some(Components::Values(p));
            }
        }
        Ok(scene)
    }
}

/// The index of `coordinate` among `names`, or `coordinate` read as a 0-based index.
fn coordinate_index(names: &[String], coordinate: &str) -> Option<usize> {
    names
        .iter()
        .position(|name| *name == coordinate)
        .or_else(|| coordinate.parse().ok().filter(|&i: &usize| i < names.len()))
}

/// A resolved initial state on ℝᴺ, as vectors.
enum InitialVectors {
    /// (q0, q̇0).
    Velocity { q: Vec<f64>, v: Vec<f64> },
    /// (q0, p0).
    Momentum { q: Vec<f64>, p: Vec<f64> },
}

/// Resolves a scene's initial state on ℝᴺ (its own fields, else the model's defaults for the
/// scene's parameters) as vectors, with the model's coordinate names.
struct ResolveInitial<'a> {
    scene: &'a Scene,
}

impl ModelVisitor for ResolveInitial<'_> {
    type Output = Result<(Vec<String>, InitialVectors), SceneError>;

    fn visit<M: ZooModel<N>, N: Dimension>(self, mut model: M) -> Self::Output
    where
        DefaultAllocator: Allocator<N> + Allocator<N, N>,
    {
        let (_, initial, _, _) = self.scene.resolve(&mut model)?;
        let names = model.coordinate_names();
        let vector = |x: &nalgebra::OVector<f64, N>| x.iter().copied().collect::<Vec<f64>>();
        Ok((
            names,
            match initial {
                svi::Initial::Velocity { q, v } => InitialVectors::Velocity {
                    q: vector(&q),
                    v: vector(&v),
                },
                svi::Initial::Momentum { q, p } => InitialVectors::Momentum {
                    q: vector(&q),
                    p: vector(&p),
                },
            },
        ))
    }
}

/// The names of a scene's model: its parameters and (on ℝᴺ) its coordinates.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelNames {
    /// The model's parameter names.
    pub parameters: Vec<&'static str>,
    /// The configuration coordinates (`None` for a rigid body on SO(3) and for a chain, whose
    /// n coordinates are numbered, not named).
    pub coordinates: Option<Vec<String>>,
    /// Whether the model is a chain of run-time size (zoo or text): its table has no column
    /// per coordinate, and its initial state is given site by site in the scene.
    pub chain: bool,
    /// For a model on a Lie group other than SO(3): its dimension N and the number E of its
    /// configuration's stored entries (the table's columns of g, ξ and μ).
    pub group: Option<(usize, usize)>,
}

impl GroupModelVisitor for ModelNamesOf {
    type Output = ModelNames;
    fn visit<M: GroupZooModel<N, E>, const N: usize, const E: usize>(self, model: M) -> ModelNames {
        ModelNames {
            parameters: model.parameters().iter().map(|(name, _)| *name).collect(),
            coordinates: None,
            chain: false,
            group: Some((N, E)),
        }
    }
}

impl ModelVisitor for ModelNamesOf {
    type Output = ModelNames;
    fn visit<M: ZooModel<N>, N: Dimension>(self, model: M) -> ModelNames
    where
        DefaultAllocator: Allocator<N> + Allocator<N, N>,
    {
        ModelNames {
            parameters: model.parameters().iter().map(|(name, _)| *name).collect(),
            coordinates: Some(model.coordinate_names()),
            chain: false,
            group: None,
        }
    }
}

impl LocalModelVisitor for ModelNamesOf {
    type Output = ModelNames;
    fn visit<M: LocalZooModel>(self, model: M) -> ModelNames {
        ModelNames::chain(model.parameters())
    }
}

impl ModelNames {
    /// The names of a chain with these parameters.
    fn chain(parameters: Vec<(&'static str, f64)>) -> ModelNames {
        ModelNames {
            parameters: parameters.iter().map(|(name, _)| *name).collect(),
            coordinates: None,
            chain: true,
            group: None,
        }
    }
}

impl RigidModelVisitor for ModelNamesOf {
    type Output = ModelNames;
    fn visit<M: RigidZooModel>(self, model: M) -> ModelNames {
        ModelNames {
            parameters: model.parameters().iter().map(|(name, _)| *name).collect(),
            coordinates: None,
            chain: false,
            group: None,
        }
    }
}

/// Visits a model for its [`ModelNames`].
struct ModelNamesOf;

/// Check the axes against the scene's model before any member runs: every parameter is one
/// of the model's, every initial component one of its coordinates (ℝᴺ scenes only). Returns
/// the model's names.
pub fn check_axes(scene: &Scene, axes: &[Axis]) -> Result<ModelNames, SceneError> {
    let names = match scene.space() {
        SpaceKind::Vector => match scene.text() {
            Some(text) => match text? {
                Text::Model(model) => ModelNames {
                    parameters: model.parameters().iter().map(|(name, _)| *name).collect(),
                    coordinates: Some(
                        model
                            .coordinate_names()
                            .iter()
                            .map(|name| name.to_string())
                            .collect(),
                    ),
                    chain: false,
                    group: None,
                },
                Text::Chain(chain) => ModelNames::chain(chain.parameters()),
            },
            None if scene.is_local() => svi_models::visit_local_model(&scene.model, ModelNamesOf)
                .unwrap_or_else(|| unreachable!("is_local: a runtime-dimension model")),
            None => svi_models::visit_model(&scene.model, ModelNamesOf)?,
        },
        SpaceKind::Group if scene.is_rigid() => {
            svi_models::visit_rigid_model(&scene.model, ModelNamesOf)
                .unwrap_or_else(|| unreachable!("the space of a scene is its model's"))
        }
        SpaceKind::Group => svi_models::visit_group_model(&scene.model, ModelNamesOf)
            .unwrap_or_else(|| unreachable!("the space of a scene is its model's")),
    };
    // The components varied so far, as (field, index) and as written.
    let mut varied: Vec<((InitialField, usize), String)> = Vec::new();
    for axis in axes {
        match &axis.target {
            Target::Parameter(name) if !names.parameters.contains(&name.as_str()) => {
                return Err(SceneError::InvalidOption {
                    option: "--param",
                    reason: format!(
                        "model '{}' has no parameter '{name}' (parameters: {})",
                        scene.model,
                        names.parameters.join(", ")
                    ),
                });
            }
            Target::Initial { field, coordinate } => {
                let Some(coordinates) = &names.coordinates else {
                    let reason = if names.chain {
                        format!(
                            "varies q, v or p of models with named coordinates; '{}' is a \
                             chain, whose initial state the scene gives site by site (vary \
                             its parameters with --param)",
                            scene.model_name()
                        )
                    } else {
                        format!(
                            "varies q, v or p of scenes on ℝᴺ; '{}' lives on a Lie group",
                            scene.model
                        )
                    };
                    return Err(SceneError::NotApplicable {
                        option: "--initial",
                        reason,
                    });
                };
                let Some(index) = coordinate_index(coordinates, coordinate) else {
                    return Err(SceneError::InvalidOption {
                        option: "--initial",
                        reason: format!(
                            "model '{}' has no coordinate '{coordinate}' (coordinates: {}; or \
                             an index from 0)",
                            scene.model,
                            coordinates.join(", ")
                        ),
                    });
                };
                let key = (*field, index);
                if let Some((_, first)) = varied.iter().find(|(seen, _)| *seen == key) {
                    return Err(SceneError::InvalidOption {
                        option: "--initial",
                        reason: format!(
                            "{} and {first} vary the same component ({} of coordinate {}); \
                             give it once",
                            axis.name(),
                            field.name(),
                            coordinates[index]
                        ),
                    });
                }
                varied.push((key, axis.name()));
            }
            Target::Parameter(_) => {}
        }
    }
    Ok(names)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grids_lists_and_ranges_parse() {
        let axis = parse_parameter_axis("e=0.1:0.9:81").unwrap();
        assert_eq!(axis.name(), "e");
        let points = axis.values.points().unwrap();
        assert_eq!(points.len(), 81);
        assert_eq!((points[0], points[80]), (0.1, 0.9));
        assert_eq!(points[40], 0.1 + 40.0 * (0.8 / 80.0));
        let axis = parse_parameter_axis("e=0.1,0.3,0.5").unwrap();
        assert_eq!(axis.values, Values::List(vec![0.1, 0.3, 0.5]));
        let axis = parse_parameter_axis("e=0:1:3,1.2").unwrap();
        assert_eq!(axis.values, Values::List(vec![0.0, 0.5, 1.0, 1.2]));
        assert!(parse_parameter_axis("e=0:1,2").is_err());
        let axis = parse_parameter_axis("e=0:0.9").unwrap();
        assert_eq!(axis.values, Values::Range { lo: 0.0, hi: 0.9 });
        let axis = parse_initial_axis("q.alpha1=-3:3:5").unwrap();
        assert_eq!(axis.name(), "q.alpha1");
        assert_eq!(axis.values.points().unwrap(), [-3.0, -1.5, 0.0, 1.5, 3.0]);
        assert_eq!(linspace(2.0, 3.0, 1), [2.0]);
    }

    #[test]
    fn bad_axes_name_the_option_and_the_fault() {
        for (text, fault) in [
            ("e=0.1:0.9:0", "COUNT is 0"),
            ("e=0.9:0.1:3", "exceeds HI"),
            ("e=0.1:inf:3", "not a finite number"),
            ("e=nan", "not a finite number"),
            ("e=0.1:0.9:x", "not a whole number"),
            ("e=0.1:0.9:-1", "not a whole number"),
            ("e=1:2:3:4", "expected LO:HI:COUNT"),
            ("e=-1e308:1e308", "overflows"),
            ("e", "expected NAME=SPEC"),
            ("=1", "the name is empty"),
            ("e=a,b", "'a' is not a number"),
        ] {
            let error = parse_parameter_axis(text).unwrap_err();
            let message = error.to_string();
            assert!(message.starts_with("invalid --param: "), "{message}");
            assert!(message.contains(fault), "{text}: {message}");
            assert!(error.is_bad_input());
        }
        for text in ["alpha1=0:1:2", "x.alpha1=0:1:2", "q.=1"] {
            let message = parse_initial_axis(text).unwrap_err().to_string();
            assert!(message.starts_with("invalid --initial: "), "{message}");
        }
    }

    #[test]
    fn grids_are_cartesian_products_first_axis_slowest() {
        let axes = [
            parse_parameter_axis("a=1,2").unwrap(),
            parse_parameter_axis("b=10:30:3").unwrap(),
        ];
        let values: Vec<Vec<f64>> = members(&axes, None)
            .unwrap()
            .into_iter()
            .map(|m| m.values)
            .collect();
        assert_eq!(
            values,
            [
                [1.0, 10.0],
                [1.0, 20.0],
                [1.0, 30.0],
                [2.0, 10.0],
                [2.0, 20.0],
                [2.0, 30.0]
            ]
        );
        assert_eq!(members(&[], None).unwrap().len(), 1);
        let twice = [axes[0].clone(), axes[0].clone()];
        assert!(
            members(&twice, None)
                .unwrap_err()
                .to_string()
                .contains("twice")
        );
        let range = [parse_parameter_axis("e=0:1").unwrap()];
        assert!(
            members(&range, None)
                .unwrap_err()
                .to_string()
                .contains("--random")
        );
        let huge = [
            parse_parameter_axis("a=0:1:100000").unwrap(),
            parse_parameter_axis("b=0:1:100000").unwrap(),
        ];
        assert!(members(&huge, None).is_err());
    }

    #[test]
    fn random_draws_repeat_with_the_seed_and_stay_in_range() {
        let axes = [
            parse_parameter_axis("e=0.1:0.9").unwrap(),
            parse_parameter_axis("k=1,2,3").unwrap(),
        ];
        let draw = |seed| members(&axes, Some(Random { count: 100, seed })).unwrap();
        assert_eq!(draw(7), draw(7));
        assert_ne!(draw(7), draw(8));
        for member in draw(7) {
            assert!((0.1..=0.9).contains(&member.values[0]));
            assert!([1.0, 2.0, 3.0].contains(&member.values[1]));
        }
        let zero = members(&axes, Some(Random { count: 0, seed: 1 }));
        assert!(zero.unwrap_err().to_string().contains("--random"));
    }

    #[test]
    fn a_member_scene_is_the_scene_with_its_values() {
        let scene = Scene::load("double-pendulum").unwrap();
        let axes = [
            parse_parameter_axis("g=9.81,1").unwrap(),
            parse_initial_axis("q.alpha2=0.25").unwrap(),
            parse_initial_axis("v.0=0.5").unwrap(),
        ];
        check_axes(&scene, &axes).unwrap();
        let member = Member {
            values: vec![1.0, 0.25, 0.5],
        };
        let applied = member.apply(&axes, &scene).unwrap();
        assert_eq!(applied.parameters["g"], 1.0);
        assert_eq!(applied.initial.q, Some(Components::Values(vec![1.0, 0.25])));
        assert_eq!(applied.initial.v, Some(Components::Values(vec![0.5, 0.0])));
        let unknown = [parse_parameter_axis("x=1").unwrap()];
        let message = check_axes(&scene, &unknown).unwrap_err().to_string();
        assert!(message.contains("no parameter 'x'"), "{message}");
        let unknown = [parse_initial_axis("q.beta=1").unwrap()];
        let message = check_axes(&scene, &unknown).unwrap_err().to_string();
        assert!(message.contains("no coordinate 'beta'"), "{message}");
        let rigid = Scene::load("rigid-body").unwrap();
        assert!(check_axes(&rigid, &axes[1..]).is_err());
    }
}
