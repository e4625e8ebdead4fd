//! The models on Lie groups other than SO(3): registry, parameter validation, and that their
//! declarations hold — each symmetry generator leaves L unchanged (d/ds L(exp(sζ)g, ξ) = 0),
//! the defaults lie in the group, and the falling body's exact solution starts at its initial
//! state.

use nalgebra::SVector;
use svi::Error;
use svi::lie_group::{GroupDefaults, GroupSymmetries, LieGroup, check_generators, symmetry_defect};
use svi_models::{
    DualSpin, FallingBody, GROUP_MODEL_NAMES, GroupModelVisitor, GroupZooModel, visit_group_model,
};

struct Name;

impl GroupModelVisitor for Name {
    type Output = &'static str;
    fn visit<M: GroupZooModel<N, E>, const N: usize, const E: usize>(
        self,
        model: M,
    ) -> &'static str {
        model.name()
    }
}

#[test]
fn every_group_name_visits_the_model_of_that_name() {
    assert_eq!(
        GROUP_MODEL_NAMES,
        ["falling-body", "dual-spin", "spherical-chain"]
    );
    for &name in GROUP_MODEL_NAMES {
        assert_eq!(visit_group_model(name, Name), Some(name));
    }
    assert_eq!(visit_group_model("falling-bdy", Name), None);
}

/// Checks the declarations of one model.
struct Declarations;

impl GroupModelVisitor for Declarations {
    type Output = ();
    fn visit<M: GroupZooModel<N, E>, const N: usize, const E: usize>(self, mut model: M) {
        let name = model.name();
        // Parameters: every one can be set to its value; unknown names and bad values fail.
        for (parameter, value) in model.parameters() {
            model.set_parameter(parameter, value).unwrap();
            let error = model.set_parameter(parameter, f64::NAN).unwrap_err();
            assert!(matches!(error, Error::InvalidParameter { .. }), "{name}");
            let error = model.set_parameter(parameter, -1.0).unwrap_err();
            assert!(matches!(error, Error::InvalidParameter { .. }), "{name}");
        }
        let error = model.set_parameter("nonsense", 1.0).unwrap_err();
        assert!(error.to_string().contains("no such parameter"), "{error}");
        assert!(model.default_step() > 0.0 && model.default_horizon() > model.default_step());

        // The default state is in the group; every generator is one, and a symmetry at it
        // and at a state far from it.
        let (g0, xi0) = model.initial_state();
        assert!(M::Group::defect(&g0) < 1e-14, "{name}");
        check_generators(&model).unwrap();
        let far = (
            M::Group::compose(
                &g0,
                &M::Group::exp(&SVector::from_fn(|i, _| 0.4 * (i as f64 + 0.3).sin())),
            ),
            xi0.map(|x| -0.7 * x + 0.3),
        );
        for (g, xi) in [(g0, xi0), far] {
            for index in 0..model.generator_count() {
                let defect = symmetry_defect(&model, index, &g, &xi);
                assert!(
                    defect < 1e-14,
                    "{name}: {} changes L by {defect:e}",
                    model.momentum_name(index)
                );
            }
        }
    }
}

#[test]
fn group_models_declare_true_symmetries_and_check_their_parameters() {
    for &name in GROUP_MODEL_NAMES {
        visit_group_model(name, Declarations).unwrap();
    }
}

/// A generator that is not a symmetry is measured as one that is not: gravity breaks the
/// vertical translation of the falling body, and the rotation about a horizontal axis.
#[test]
fn a_false_symmetry_has_a_defect() {
    struct Vertical(FallingBody, SVector<f64, 6>);
    impl svi::lie_group::GroupLagrangian<6, 12> for Vertical {
        type Group = svi::lie_group::RigidMotions;
        fn lagrangian<D: svi::Scalar>(&self, g: &SVector<D, 12>, xi: &SVector<D, 6>) -> D {
            self.0.lagrangian(g, xi)
        }
    }
    impl GroupSymmetries<6, 12> for Vertical {
        fn generator_count(&self) -> usize {
            1
        }
        fn momentum_name(&self, _: usize) -> &'static str {
            "p_z"
        }
        fn generator(&self, _: usize) -> SVector<f64, 6> {
            self.1
        }
    }
    let body = FallingBody::default();
    let (g0, xi0) = body.initial_state();
    for generator in [
        SVector::from([0.0, 0.0, 0.0, 0.0, 0.0, 1.0]),
        SVector::from([1.0, 0.0, 0.0, 0.0, 0.0, 0.0]),
    ] {
        let defect = symmetry_defect(&Vertical(body, generator), 0, &g0, &xi0);
        assert!(defect > 1e-3, "{defect:e}");
    }
    // And a zero-length generator is a typed error naming it.
    let error = check_generators(&Vertical(body, SVector::zeros())).unwrap_err();
    assert!(
        matches!(error, Error::InvalidParameter { .. }) && error.to_string().contains("p_z"),
        "{error}"
    );
    let error = check_generators(&Vertical(body, SVector::from_element(f64::NAN))).unwrap_err();
    assert!(error.to_string().contains("non-finite"), "{error}");
}

#[test]
fn the_falling_body_exact_solution_starts_at_its_initial_state() {
    let body = FallingBody::default();
    let (g0, xi0) = body.initial_state();
    let (g, xi) = body.exact_solution(&g0, &xi0, 0.0).unwrap();
    assert!((g - g0).amax() < 1e-14 && (xi - xi0).amax() < 1e-14);
}

#[test]
fn the_rotor_inertia_stays_below_the_third_moment() {
    let mut satellite = DualSpin::default();
    let error = satellite.set_parameter("j", 3.0).unwrap_err();
    assert!(error.to_string().contains("below i3"), "{error}");
    let error = satellite.set_parameter("i3", 0.4).unwrap_err();
    assert!(error.to_string().contains("below i3"), "{error}");
    satellite.set_parameter("j", 2.0).unwrap();
    assert_eq!(satellite.rotor, 2.0);
}
