//! A scene resolved against its model: the scene's parameters applied, then the initial
//! time and state, the step and the horizon (scene values, else the model's defaults), on
//! ℝᴺ, on runtime-sized ℝⁿ and on SO(3).

use nalgebra::DefaultAllocator;
use nalgebra::allocator::Allocator;
use svi::lie_group::{GroupInitial, RigidInitial, check_generators};
use svi::model::text::site_values;
use svi::{Dimension, Dyn, Initial, LagrangianExt};
use svi_models::{GroupZooModel, LocalZooModel, RigidZooModel, ZooModel};

use crate::scene::schema::Diagnostic;
use crate::scene::{Scene, SceneError, group, limits, rigid, vector};

impl Scene {
    /// Apply the scene's parameters to a model on ℝᴺ and resolve the initial time and state,
    /// the step and the horizon (scene values, else the model's defaults).
    pub fn resolve<M: ZooModel<N>, N: Dimension>(
        &self,
        model: &mut M,
    ) -> Result<(f64, Initial<N>, f64, f64), SceneError>
    where
        DefaultAllocator: Allocator<N> + Allocator<N, N>,
    {
        for (name, value) in &self.parameters {
            model.set_parameter(name, *value)?;
        }
        let (default_t0, default_q, default_v) = model.initial_state();
        let initial = vector::initial(&self.initial, model.name(), default_q, default_v)?;
        let t0 = self.initial.t0.unwrap_or(default_t0);
        if self.wants_explicitly(Diagnostic::Momentum) && model.generator_count() == 0 {
            return Err(self.not_measurable(
                "--diagnostics momentum (output.diagnostics)",
                "has no symmetry, hence no Noether momentum to measure",
            ));
        }
        if self.wants_explicitly(Diagnostic::Solution) {
            let velocity = match &initial {
                Initial::Velocity { v, .. } => Some(v.clone()),
                Initial::Momentum { q, p } => model.velocity(t0, q, p, p).ok(),
            };
            let q = match &initial {
                Initial::Velocity { q, .. } | Initial::Momentum { q, .. } => q,
            };
            // A velocity that cannot be computed is the run's to report.
            if velocity.is_some_and(|v| model.exact_solution(t0, q, &v, t0).is_none()) {
                return Err(self.not_measurable(
                    "--diagnostics solution (output.diagnostics)",
                    "has no exact solution for this initial state to measure against",
                ));
            }
        }
        Ok((
            t0,
            initial,
            self.run.h.unwrap_or_else(|| model.default_step()),
            self.run.t_end.unwrap_or_else(|| model.default_horizon()),
        ))
    }

    /// [`Scene::resolve`] for a runtime-dimension model: its parameters (the size `n` among
    /// them) first, then the initial state of `[initial]` (vectors of n components) or the
    /// model's default for that n.
    pub fn resolve_local<M: LocalZooModel>(
        &self,
        model: &mut M,
    ) -> Result<(f64, svi::Initial<Dyn>, f64, f64), SceneError> {
        for (name, value) in &self.parameters {
            model.set_parameter(name, *value)?;
        }
        // The memory is checked before any vector of n components is made.
        let spec = self.method_spec()?;
        let outputs = self.output.output_times.as_ref().map_or(0, Vec::len);
        let n = model.dimension();
        let estimate = limits::chain_memory(
            n,
            spec.name(),
            spec.points_in_use(),
            M::STRUCTURE == svi::Structure::ConstantMass,
            outputs,
        );
        let what = format!(
            "{} with n = {n}, {}{}",
            model.name(),
            spec.name(),
            if outputs > 0 {
                format!(" and {outputs} output times of 3n numbers each")
            } else {
                String::new()
            }
        );
        limits::check_memory("n (--param n, or --output-times)", estimate, &what)?;
        let (default_t0, default_q, default_v) = model.initial_state();
        // A chain written as text stores its families site by site; a zoo chain is one.
        let families = if self.is_text_chain() {
            self.coordinates.as_ref().map_or(1, Vec::len)
        } else {
            1
        };
        let parameters = model.parameters();
        let sites = |field: &'static str, expressions: &[String]| {
            site_values(
                expressions,
                families,
                &format!("initial.{field}"),
                &parameters,
                n / families,
            )
            .map_err(SceneError::from)
        };
        let initial =
            vector::local_initial(&self.initial, model.name(), default_q, default_v, &sites)?;
        Ok((
            self.initial.t0.unwrap_or(default_t0),
            initial,
            self.run.h.unwrap_or_else(|| model.default_step()),
            self.run.t_end.unwrap_or_else(|| model.default_horizon()),
        ))
    }

    /// [`Scene::resolve`] for a rigid body on SO(3) (t0 defaults to 0, the horizon to t0
    /// plus the model's default duration).
    pub fn resolve_rigid<M: RigidZooModel>(
        &self,
        model: &mut M,
    ) -> Result<(f64, RigidInitial, f64, f64), SceneError> {
        for (name, value) in &self.parameters {
            model.set_parameter(name, *value)?;
        }
        let (default_r, default_omega) = model.initial_state();
        let initial = rigid::initial(&self.initial, default_r, default_omega)?;
        if self.wants_explicitly(Diagnostic::Momentum) && model.axis_count() == 0 {
            return Err(self.not_measurable(
                "--diagnostics momentum (output.diagnostics)",
                "has no symmetry axis, hence no conserved angular momentum to measure",
            ));
        }
        let (t0, h, t_end) = self.timing(model.default_step(), model.default_horizon());
        Ok((t0, initial, h, t_end))
    }

    /// [`Scene::resolve`] for a model on a Lie group other than SO(3) ([`group`]; t0
    /// defaults to 0, the horizon to t0 plus the model's default duration). A symmetry
    /// generator of zero length is an error ([`check_generators`]), as are momentum or
    /// solution diagnostics the model cannot give.
    pub fn resolve_group<M: GroupZooModel<N, E>, const N: usize, const E: usize>(
        &self,
        model: &mut M,
    ) -> Result<(f64, GroupInitial<N, E>, f64, f64), SceneError> {
        for (name, value) in &self.parameters {
            model.set_parameter(name, *value)?;
        }
        check_generators(model)?;
        let (default_g, default_xi) = model.initial_state();
        let initial = group::initial::<M::Group, N, E>(&self.initial, default_g, default_xi)?;
        if self.wants_explicitly(Diagnostic::Momentum) && model.generator_count() == 0 {
            return Err(self.not_measurable(
                "--diagnostics momentum (output.diagnostics)",
                "has no symmetry generator, hence no conserved momentum to measure",
            ));
        }
        if self.wants_explicitly(Diagnostic::Solution)
            && model.exact_solution(&default_g, &default_xi, 0.0).is_none()
        {
            return Err(self.not_measurable(
                "--diagnostics solution (output.diagnostics)",
                "has no exact solution to measure against",
            ));
        }
        let (t0, h, t_end) = self.timing(model.default_step(), model.default_horizon());
        Ok((t0, initial, h, t_end))
    }

    /// The start time (default 0), the step and the horizon (default: t0 plus the model's
    /// default duration) of a scene on a Lie group, whose models start at 0.
    fn timing(&self, default_step: f64, default_duration: f64) -> (f64, f64, f64) {
        let t0 = self.initial.t0.unwrap_or(0.0);
        (
            t0,
            self.run.h.unwrap_or(default_step),
            self.run.t_end.unwrap_or(t0 + default_duration),
        )
    }
}
