//! What is particular to rigid-body scenes on SO(3): the initial attitude and angular
//! velocity of `[initial]`, and the Lie-group integrator with its form.
//!
//! A rigid-body scene has a rigid-body model (`svi_models::RIGID_MODEL_NAMES`) and an
//! attitude instead of a configuration vector:
//!
//! ```toml
//! model = "heavy-top"
//!
//! [parameters]          # absent: the model's defaults
//! m = 1.0
//!
//! [initial]             # optional
//! rotation = [0.5, 0.0, 0.0]   # R0 = exp(rotation^), or quaternion = [w, x, y, z]
//! omega = [0.0, 0.0, 10.0]     # body angular velocity, or momentum = [...] (body)
//!
//! [method]
//! name = "lie-svi"      # or "lie-svi-reduced", with options: "lie-svi:3/3", "lie-svi-reduced:4"
//! points = 3            # Chebyshev–Gauss–Lobatto points (default 3), on top of name
//! quadrature = 3        # Gauss–Legendre points (default = points), on top of name
//! form = "full"         # or "reduced" (discrete Euler–Poincaré; G-invariant models only);
//!                       # name = "lie-svi-reduced" is form = "reduced"
//!
//! [run]                 # as for every scene, adaptivity and recovery included
//! h = 0.01
//! t_end = 20.0
//!
//! [output]
//! trajectory = "top.csv"      # t, quaternion, rotation matrix, Ω, Π, energy, ‖RᵀR − I‖
//! every = 10
//! diagnostics = ["energy", "momentum"]   # the invariants and ‖RᵀR − I‖ unless "none"
//! ```

use nalgebra::{SMatrix, SVector};
use svi::MethodSpec;
use svi::lie_group::so3::exp;
use svi::lie_group::{Form, LieSvi, RigidInitial};

use crate::report::csv::Float;
use crate::scene::error::SceneError;
use crate::scene::schema::{FormName, InitialSection};

/// The name of the rigid-body method in summaries (whichever form; the summary's `form`
/// says which).
pub const METHOD_NAME: &str = "lie-svi";

/// The library's form of a form name.
pub fn form(name: FormName) -> Form {
    match name {
        FormName::Full => Form::Full,
        FormName::Reduced => Form::Reduced,
    }
}

/// The name of a form, as written in scenes and summaries.
pub fn form_name(form: Form) -> &'static str {
    match form {
        Form::Full => "full",
        Form::Reduced => "reduced",
    }
}

/// The Lie-group integrator of `spec` (`lie-svi` or `lie-svi-reduced` with its options) in
/// the form `form` if given. An error names a method that is not for rigid bodies or a form
/// that contradicts `lie-svi-reduced`.
pub fn method(spec: MethodSpec, form_name: Option<FormName>) -> Result<LieSvi, SceneError> {
    let mut method = spec.lie_svi()?;
    if let Some(name) = form_name {
        if method.form == Form::Reduced && name == FormName::Full {
            return Err(svi::Error::invalid(
                "form",
                format!(
                    "form \"full\" contradicts method '{spec}' (use lie-svi for the full form)"
                ),
            )
            .into());
        }
        method = method.with_form(form(name));
    }
    Ok(method)
}

/// The initial state of `section`: the attitude (rotation vector or quaternion, else
/// `default_r`) with the body angular velocity or momentum (else `default_omega`).
pub fn initial(
    section: &InitialSection,
    default_r: SMatrix<f64, 3, 3>,
    default_omega: SVector<f64, 3>,
) -> Result<RigidInitial, SceneError> {
    let r = match (&section.rotation, &section.quaternion) {
        (Some(rotation), _) => exp(&fixed::<3>("rotation", rotation)?),
        (None, Some(q)) => rotation_from_quaternion(&fixed::<4>("quaternion", q)?)?,
        (None, None) => default_r,
    };
    Ok(match (&section.omega, &section.momentum) {
        (Some(omega), _) => RigidInitial::Velocity {
            r,
            omega: fixed::<3>("omega", omega)?,
        },
        (None, Some(momentum)) => RigidInitial::Momentum {
            r,
            momentum: fixed::<3>("momentum", momentum)?,
        },
        (None, None) => RigidInitial::Velocity {
            r,
            omega: default_omega,
        },
    })
}

/// Check the pairs of `[initial]` that exclude each other on SO(3).
pub fn check_initial(section: &InitialSection) -> Result<(), SceneError> {
    for (first, second, pair) in [
        (
            &section.rotation,
            &section.quaternion,
            "rotation and quaternion",
        ),
        (&section.omega, &section.momentum, "omega and momentum"),
    ] {
        if first.is_some() && second.is_some() {
            return Err(svi::Error::invalid(
                "initial",
                format!("both {pair} are given: give one of them"),
            )
            .into());
        }
    }
    Ok(())
}

/// Read a fixed-length vector from a scene field (an error names the field and the length).
pub(crate) fn fixed<const K: usize>(
    field: &str,
    values: &[f64],
) -> Result<SVector<f64, K>, SceneError> {
    if values.len() != K {
        return Err(svi::Error::invalid(
            format!("initial.{field}"),
            format!("{} components; need {K}", values.len()),
        )
        .into());
    }
    Ok(SVector::from_iterator(values.iter().copied()))
}

/// The rotation matrix of a unit quaternion (w, x, y, z).
fn rotation_from_quaternion(q: &SVector<f64, 4>) -> Result<SMatrix<f64, 3, 3>, SceneError> {
    let norm = q.norm();
    if !norm.is_finite() || (norm - 1.0).abs() > 1e-10 {
        return Err(svi::Error::invalid(
            "initial.quaternion",
            format!("norm {}; a unit quaternion is needed", Float(norm)),
        )
        .into());
    }
    Ok(svi::lie_group::rotation(&[q[0], q[1], q[2], q[3]]))
}
