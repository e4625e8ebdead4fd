//! The symmetric compositions of Störmer–Verlet ([`crate::Composition`]: `yoshida4`,
//! `kahan-li6`, `kahan-li8`) on runtime-sized ℝⁿ: the stages of
//! [`crate::method::variational::composition`] taken by the kick–drift–kick of
//! [`super::verlet`], one assembly of ∂L/∂q per stage (the force at a stage's end is the
//! next stage's start force), O(n) per stage and no allocation.

use crate::Composition;
use crate::error::{Error, StepFailure};
use crate::method::local::LocalMethod;
use crate::method::local::verlet::LocalVerletWorkspace;
use crate::method::space::DynState;
use crate::method::{MethodInfo, StepReport};
use crate::model::local::LocalLagrangian;
use nalgebra::DVector;

/// Buffers of a composition run on runtime-sized ℝⁿ: Störmer–Verlet's, and the start and
/// increment of one stage.
#[derive(Debug)]
pub struct LocalCompositionWorkspace {
    base: LocalVerletWorkspace,
    from: DynState,
    stage: DynState,
}

impl LocalMethod for Composition {
    type Workspace = LocalCompositionWorkspace;

    fn info(&self) -> MethodInfo {
        MethodInfo {
            name: self.scheme().name(),
            order: self.scheme().order(),
            ..LocalMethod::info(&self.base)
        }
    }

    fn local_workspace<L: LocalLagrangian>(
        &self,
        model: &L,
        h: f64,
    ) -> Result<LocalCompositionWorkspace, Error> {
        let n = model.dimension();
        Ok(LocalCompositionWorkspace {
            base: self.base.local_workspace(model, h)?,
            from: DynState::zeros(n),
            stage: DynState::zeros(n),
        })
    }

    fn local_step<L: LocalLagrangian>(
        &self,
        model: &L,
        workspace: &mut LocalCompositionWorkspace,
        t: f64,
        h: f64,
        state: &DynState,
        increment: &mut DynState,
    ) -> Result<StepReport, StepFailure> {
        let LocalCompositionWorkspace { base, from, stage } = workspace;
        let mut report = StepReport::default();
        self.stages(
            (t, h),
            state,
            (from, stage, increment),
            |t, size, from, stage| {
                report += self.base.local_step(model, base, t, size, from, stage)?;
                Ok(())
            },
        )?;
        Ok(report)
    }

    fn local_restart(&self, workspace: &mut LocalCompositionWorkspace) {
        self.base.local_restart(&mut workspace.base);
    }

    fn local_velocity<L: LocalLagrangian>(
        &self,
        model: &L,
        workspace: &LocalCompositionWorkspace,
        t: f64,
        q: &DVector<f64>,
        p: &DVector<f64>,
        v: &mut DVector<f64>,
    ) -> Result<(), Error> {
        self.base.local_velocity(model, &workspace.base, t, q, p, v)
    }
}
