//! Pseudospectral scenes: a complex (Schrödinger-type) field of the zoo
//! ([`svi_models::SPECTRAL_MODEL_NAMES`]) run by the pseudospectral integrators
//! ([`svi::field::pseudospectral`]). Their own format and run path (`run/spectral.rs`):
//!
//! ```toml
//! # The NLS soliton (the first line, a comment, describes the scene)
//! model = "nls-soliton"
//! method = "svi:4"        # midpoint (the seed's linear-in-time VI), svi:P or svi:P/M
//!                         # (Galerkin in time through P CGL points, M = P − 1 Gauss
//!                         # points: Gauss collocation, order 2(P − 1)), or strang
//!
//! [parameters]            # model parameters (absent: the model's defaults)
//! eta = 1.0
//!
//! [mesh]
//! points = 512            # Fourier modes = nodes in space, even (absent: the model's default)
//!
//! [run]                   # absent: the model's default step and horizon
//! h = 0.05
//! t_end = 10.0            # the run ends at the first level at or after it
//!
//! [output]
//! trajectory = "soliton.csv"   # the field as CSV, rows t,x,abs,re,im (absent: none)
//! every = 10                   # every 10th time level (default 1)
//! # plot = "soliton.svg"       # a space-time picture of |ψ| (needs trajectory)
//! ```
//!
//! From the command line, `--method` (midpoint or svi:P[/M]; Strang is the scene
//! `nls-soliton-strang` or `method = "strang"` in a file), `--h`, `--t-end`,
//! `--param NAME=VALUE` (`--param points=N` sets the modes), `--out`, `--every` and `--plot`
//! apply; every other run flag is an error ([`SceneError::NotApplicable`]).

use std::collections::BTreeMap;
use std::path::PathBuf;

use serde::Deserialize;
use svi::field::pseudospectral::TimeScheme;
use svi_models::SPECTRAL_MODEL_NAMES;

use crate::scene::error::SceneError;
use crate::scene::field::{FieldRunSection, SpaceTimeFields, load_space_time, reject_other_flags};
use crate::scene::overrides::Overrides;

/// The built-in pseudospectral scenes, as (name, TOML text).
pub const SPECTRAL_SCENES: &[(&str, &str)] = &[
    (
        "schrodinger-packet",
        include_str!("../../scenes/schrodinger-packet.toml"),
    ),
    ("nls-soliton", include_str!("../../scenes/nls-soliton.toml")),
    (
        "nls-soliton-strang",
        include_str!("../../scenes/nls-soliton-strang.toml"),
    ),
];

/// A pseudospectral scene (see the module documentation).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpectralScene {
    /// The model, one of [`SPECTRAL_MODEL_NAMES`].
    pub model: String,
    /// The time scheme: `midpoint`, `svi:P`, `svi:P/M` or `strang` (absent: `midpoint`).
    pub method: Option<String>,
    /// Model parameters, name → value.
    #[serde(default)]
    pub parameters: BTreeMap<String, f64>,
    /// The Fourier grid.
    #[serde(default)]
    pub mesh: SpectralMeshSection,
    /// Step and horizon.
    #[serde(default)]
    pub run: FieldRunSection,
    /// Outputs.
    #[serde(default)]
    pub output: SpectralOutputSection,
    /// The scene file it was read from (none for a built-in scene): no output may be
    /// written over it. Not a scene field.
    #[serde(skip)]
    pub source: Option<std::path::PathBuf>,
}

/// `[mesh]` of a pseudospectral scene.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpectralMeshSection {
    /// Fourier modes (= nodes in space), even.
    pub points: Option<usize>,
}

/// `[output]` of a pseudospectral scene.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpectralOutputSection {
    /// The CSV file of the field (rows `t,x,abs,re,im`).
    pub trajectory: Option<PathBuf>,
    /// Write every k-th time level.
    pub every: Option<usize>,
    /// An SVG space-time picture of |ψ| from `trajectory` (needs it).
    pub plot: Option<PathBuf>,
}

/// The time scheme a method name selects: `midpoint` (Galerkin degree 1), `svi:P` or
/// `svi:P/M` with M = P − 1 (degree P − 1), `strang`.
pub fn time_scheme(text: &str) -> Result<TimeScheme, SceneError> {
    let bad = |reason: String| SceneError::InvalidOption {
        option: "method",
        reason: format!("'{text}': {reason}"),
    };
    let usage = "a pseudospectral scene takes midpoint, svi:P or svi:P/M (P ≥ 2 CGL points, \
                 M = P − 1 Gauss points) or strang";
    match text.trim() {
        "midpoint" => return Ok(TimeScheme::Galerkin { degree: 1 }),
        "strang" => return Ok(TimeScheme::Strang),
        _ => {}
    }
    let Some(options) = text.trim().strip_prefix("svi:") else {
        return Err(bad(usage.into()));
    };
    let (points, quadrature) = match options.split_once('/') {
        Some((points, quadrature)) => (points, Some(quadrature)),
        None => (options, None),
    };
    let points: usize = points
        .parse()
        .map_err(|_| bad(format!("'{points}' is not a number of CGL points; {usage}")))?;
    if points < 2 {
        return Err(bad(format!("{points} CGL points; {usage}")));
    }
    if let Some(quadrature) = quadrature
        && quadrature.parse::<usize>().ok() != Some(points - 1)
    {
        return Err(bad(format!(
            "Gauss points '{quadrature}': the Galerkin SVI in time integrates the kinetic term \
             exactly with M = P − 1 = {} points (Gauss collocation); {usage}",
            points - 1
        )));
    }
    Ok(TimeScheme::Galerkin { degree: points - 1 })
}

/// The name of a time scheme, as [`time_scheme`] reads it.
pub fn scheme_name(scheme: TimeScheme) -> String {
    match scheme {
        TimeScheme::Galerkin { degree: 1 } => "midpoint".into(),
        TimeScheme::Galerkin { degree } => format!("svi:{}/{degree}", degree + 1),
        TimeScheme::Strang => "strang".into(),
    }
}

impl SpectralScene {
    /// The pseudospectral scene `name_or_path` names: a built-in one, or a scene file whose
    /// `model` is a complex field model; `None` for anything else.
    pub fn load(name_or_path: &str) -> Option<Result<SpectralScene, SceneError>> {
        let loaded = load_space_time(name_or_path, SPECTRAL_SCENES, SPECTRAL_MODEL_NAMES)?;
        Some(loaded.map(|(scene, source)| SpectralScene { source, ..scene }))
    }

    /// The scene's time scheme.
    pub fn scheme(&self) -> Result<TimeScheme, SceneError> {
        time_scheme(self.method.as_deref().unwrap_or("midpoint"))
    }

    /// Put the command-line flags on top (see the module documentation).
    pub fn apply(&mut self, overrides: &Overrides) -> Result<(), SceneError> {
        reject_other_flags(overrides, true, || {
            format!(
                "'{}' is a pseudospectral scene: it takes --method (midpoint, svi:P[/M]), \
                 --h, --t-end, --param (points=N for the Fourier modes), --out, --every \
                 and --plot",
                self.model
            )
        })?;
        if let Some(method) = &overrides.run.method {
            self.method = Some(method.to_string());
        }
        self.scheme()?;
        SpaceTimeFields {
            parameters: &mut self.parameters,
            points: &mut self.mesh.points,
            run: &mut self.run,
            trajectory: &mut self.output.trajectory,
            every: &mut self.output.every,
            plot: &mut self.output.plot,
            source: self.source.as_deref(),
        }
        .apply(overrides, "Fourier modes")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_built_in_scenes_parse_and_name_complex_field_models() {
        for (name, _) in SPECTRAL_SCENES {
            let scene = SpectralScene::load(name).unwrap().unwrap();
            assert!(
                SPECTRAL_MODEL_NAMES.contains(&scene.model.as_str()),
                "{name}"
            );
            scene.scheme().unwrap();
        }
        assert!(SpectralScene::load("wave").is_none());
    }

    #[test]
    fn method_names_round_trip_and_bad_ones_are_errors() {
        for text in ["midpoint", "svi:4", "svi:4/3", "strang"] {
            let scheme = time_scheme(text).unwrap();
            assert_eq!(time_scheme(&scheme_name(scheme)).unwrap(), scheme);
        }
        assert_eq!(
            time_scheme("svi:4").unwrap(),
            TimeScheme::Galerkin { degree: 3 }
        );
        for text in ["verlet", "svi:1", "svi:x", "svi:4/4", "svi"] {
            assert!(
                matches!(
                    time_scheme(text),
                    Err(SceneError::InvalidOption {
                        option: "method",
                        ..
                    })
                ),
                "{text}"
            );
        }
    }
}
