//! The one result schema: every JSON object `svi` prints (`--json`) and the Python package
//! reads carries `schema_version` and, for a result, its `kind`, and uses the same names for
//! the same meanings across kinds — `steps`, `energy_initial`, `energy_error_max` and
//! `energy_error_final`, `momentum_error_max`, `solution_error_max` and
//! `solution_error_final`, `iterations`, `seconds`, `status`, `warnings`, `error` — with the
//! fields particular to a kind added beside them. `docs/schema/result.schema.json` documents
//! version [`SCHEMA_VERSION`] (the tests validate every `--json` output of the command-line
//! tests against it).
//!
//! Names that schema version 1 replaced are still printed beside their successors for one
//! release ([`Versioned::deprecated`]; the README's "Interface changes" lists them).

use serde::Serialize;
use serde_json::Value;

/// The version of the result schema (`schema_version` of every JSON object).
pub const SCHEMA_VERSION: u32 = 1;

/// What a JSON object of `svi` is: its `kind`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Kind {
    /// A run on ℝᴺ (zoo models, text models, chains).
    Ode,
    /// A run on a Lie group (rigid bodies on SO(3)).
    LieGroup,
    /// A multisymplectic run of a 1 + 1 field theory.
    Field,
    /// A pseudospectral run (Schrödinger, NLS).
    Pseudospectral,
    /// `svi ensemble`: a table of members.
    Ensemble,
    /// `svi compare`: a row per method.
    Comparison,
    /// A failure before any result: bad input (only `status` and `error`).
    Failure,
}

/// A result with its version, kind and the names it still prints for earlier readers.
pub trait Versioned: Serialize {
    /// The kind of result.
    fn kind(&self) -> Kind;

    /// The names schema version 1 replaced, each with its value (the value of its
    /// successor), printed after the fields.
    fn deprecated(&self) -> Vec<(&'static str, Value)> {
        Vec::new()
    }
}

/// The JSON object of a result: `schema_version`, `kind`, its fields, its deprecated names.
#[derive(Serialize)]
struct Envelope<'a, T> {
    schema_version: u32,
    kind: Kind,
    #[serde(flatten)]
    result: &'a T,
    #[serde(flatten)]
    deprecated: serde_json::Map<String, Value>,
}

/// `result` as one line of JSON, in the schema.
///
/// # Errors
/// A value serde cannot write (none of svi's results has one).
pub fn to_json<T: Versioned>(result: &T) -> serde_json::Result<String> {
    serde_json::to_string(&envelope(result))
}

/// `result` as a JSON value, in the schema.
///
/// # Errors
/// As [`to_json`].
pub fn to_value<T: Versioned>(result: &T) -> serde_json::Result<Value> {
    serde_json::to_value(envelope(result))
}

fn envelope<T: Versioned>(result: &T) -> Envelope<'_, T> {
    Envelope {
        schema_version: SCHEMA_VERSION,
        kind: result.kind(),
        result,
        deprecated: result
            .deprecated()
            .into_iter()
            .map(|(name, value)| (name.to_string(), value))
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Serialize)]
    struct Example {
        steps: usize,
        solution_error_max: f64,
    }

    impl Versioned for Example {
        fn kind(&self) -> Kind {
            Kind::Field
        }
        fn deprecated(&self) -> Vec<(&'static str, Value)> {
            vec![("error_max", self.solution_error_max.into())]
        }
    }

    #[test]
    fn a_result_carries_its_version_kind_fields_and_old_names_in_that_order() {
        let json = to_json(&Example {
            steps: 3,
            solution_error_max: 0.5,
        })
        .unwrap();
        assert_eq!(
            json,
            r#"{"schema_version":1,"kind":"field","steps":3,"solution_error_max":0.5,"error_max":0.5}"#
        );
    }
}
