//! A scene of any kind, opened once: an ODE scene (a model on ℝⁿ or a rigid body on SO(3),
//! [`Scene`]), a field scene ([`FieldScene`], the multisymplectic integrator) or a
//! pseudospectral one ([`SpectralScene`]). The front doors (`svi run`, the Python package)
//! open it, put their overrides on top and run it ([`AnyScene::run`] in `run/`), which checks
//! it once.

use crate::scene::field::FieldScene;
use crate::scene::overrides::Overrides;
use crate::scene::spectral::SpectralScene;
use crate::scene::{Scene, SceneError};

/// A scene of any kind.
#[derive(Debug, Clone)]
pub enum AnyScene {
    /// A model on ℝⁿ or a rigid body on SO(3).
    Ode(Box<Scene>),
    /// A 1 + 1 field theory on a space–time mesh.
    Field(Box<FieldScene>),
    /// A complex field on a periodic Fourier grid.
    Pseudospectral(Box<SpectralScene>),
}

impl AnyScene {
    /// The scene `name_or_path` names (a built-in scene or a scene file), of the kind its
    /// model makes it, not yet checked.
    pub fn open(name_or_path: &str) -> Result<AnyScene, SceneError> {
        if let Some(scene) = FieldScene::load(name_or_path) {
            return Ok(AnyScene::Field(Box::new(scene?)));
        }
        if let Some(scene) = SpectralScene::load(name_or_path) {
            return Ok(AnyScene::Pseudospectral(Box::new(scene?)));
        }
        Scene::open(name_or_path).map(|scene| AnyScene::Ode(Box::new(scene)))
    }

    /// Put the command-line overrides on top (each kind takes the flags it can use and
    /// refuses the others).
    pub fn overlay(&mut self, overrides: &Overrides) -> Result<(), SceneError> {
        match self {
            AnyScene::Ode(scene) => scene.overlay(overrides),
            AnyScene::Field(scene) => scene.apply(overrides),
            AnyScene::Pseudospectral(scene) => scene.apply(overrides),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_scene_opens_as_the_kind_of_its_model() {
        assert!(matches!(AnyScene::open("kepler"), Ok(AnyScene::Ode(_))));
        assert!(matches!(AnyScene::open("heavy-top"), Ok(AnyScene::Ode(_))));
        assert!(matches!(AnyScene::open("wave"), Ok(AnyScene::Field(_))));
        assert!(matches!(
            AnyScene::open("nls-soliton"),
            Ok(AnyScene::Pseudospectral(_))
        ));
        assert!(matches!(
            AnyScene::open("keppler"),
            Err(SceneError::UnknownScene { .. })
        ));
    }
}
