//! The method of a scene, by name ([`SceneMethod`]): a method of the registry
//! ([`svi::method::registry::METHODS`]: `svi:7/6`, `verlet`, ...) or, for a scene with
//! holonomic constraints ([`crate::scene::constrained`]), a constrained method
//! ([`svi::method::constrained::ConstrainedMethod`]: `rattle`, `rattle-kahan-li8`, ...), with
//! the help text that lists the constrained methods from the library's own list.

use std::fmt;
use std::str::FromStr;

use serde::Deserialize;
use svi::MethodSpec;
use svi::method::constrained::ConstrainedMethod;
use svi::method::registry;

/// The method of a scene: a method of the registry, or a constrained method for a scene with
/// constraints.
#[derive(Debug, Clone, PartialEq)]
pub enum SceneMethod {
    /// A method of [`svi::method::registry::METHODS`] (`svi:7/6`, `verlet`, ...).
    Registry(MethodSpec),
    /// A constrained method (`rattle`, `rattle-kahan-li8`, ...; see [`constrained_names`]).
    Constrained(ConstrainedMethod),
}

impl From<MethodSpec> for SceneMethod {
    fn from(spec: MethodSpec) -> Self {
        SceneMethod::Registry(spec)
    }
}

impl fmt::Display for SceneMethod {
    /// As written: `name`, `name:P`, `name:P/M`, or the constrained method's name.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SceneMethod::Registry(spec) => spec.fmt(f),
            SceneMethod::Constrained(method) => f.write_str(&method.name()),
        }
    }
}

impl FromStr for SceneMethod {
    type Err = svi::Error;

    /// A method of the registry (`name`, `name:P` or `name:P/M`), else a constrained method's
    /// name (its numbers in range: `svi:1/4` is neither); an unknown name is an error listing
    /// both.
    fn from_str(text: &str) -> Result<Self, svi::Error> {
        match text.parse::<MethodSpec>() {
            Ok(spec) => Ok(SceneMethod::Registry(spec)),
            Err(error) => match ConstrainedMethod::named(text.trim()) {
                Some(method) => method.check().map(|()| SceneMethod::Constrained(method)),
                None if registry::find(text.trim().split(':').next().unwrap_or("")).is_none() => {
                    Err(svi::Error::invalid(
                        "method",
                        format!(
                            "unknown method '{}' (known: {}; for scenes with constraints: {})",
                            text.trim(),
                            registry::known_names(),
                            constrained_names()
                        ),
                    ))
                }
                None => Err(error),
            },
        }
    }
}

impl<'de> Deserialize<'de> for SceneMethod {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let text = String::deserialize(deserializer)?;
        text.parse().map_err(serde::de::Error::custom)
    }
}

/// The constrained methods, as named in scenes and on the command line:
/// `rattle, rattle-yoshida4, ...` ([`ConstrainedMethod::names`]).
pub fn constrained_names() -> String {
    ConstrainedMethod::names().join(", ")
}

/// The help of the constrained methods, for options that take a method: one line each, with
/// its order.
pub fn constrained_help() -> String {
    let mut text = String::from(
        "Scenes with holonomic constraints (constraints = [...]) take a constrained method:",
    );
    let names = ConstrainedMethod::names();
    let width = names.iter().map(String::len).max().unwrap_or(0) + 2;
    for name in names {
        let order = ConstrainedMethod::named(&name).map_or(0, |method| method.order());
        text.push_str(&format!(
            "\n  {name:<width$}constrained variational integrator of order {order}"
        ));
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_method_is_one_of_the_registry_or_a_constrained_one_and_an_unknown_name_lists_both() {
        assert_eq!(
            "svi:7/6".parse::<SceneMethod>().unwrap(),
            SceneMethod::Registry("svi:7/6".parse().unwrap())
        );
        // Every constrained name parses; those the registry knows too (midpoint, svi:P/Q)
        // as the registry's, which a scene with constraints reads as the constrained method.
        for name in ConstrainedMethod::names() {
            let method: SceneMethod = name.parse().unwrap();
            assert_eq!(method.to_string(), name);
            if let SceneMethod::Registry(spec) = &method {
                assert!(
                    ConstrainedMethod::named(&spec.to_string()).is_some(),
                    "{name}"
                );
            }
        }
        assert!(matches!(
            "rattle".parse::<SceneMethod>().unwrap(),
            SceneMethod::Constrained(_)
        ));
        let unknown = "rk45".parse::<SceneMethod>().unwrap_err().to_string();
        assert!(
            unknown.contains("known: svi, ") && unknown.contains(&constrained_names()),
            "{unknown}"
        );
        // A known name with bad options keeps the registry's message.
        let bad = "svi:0".parse::<SceneMethod>().unwrap_err().to_string();
        assert!(!bad.contains("rattle"), "{bad}");
        // svi:P/Q out of range is no method at all, constrained or not: the error names the
        // number (it was read as a constrained method, and a scene without constraints said
        // "svi:1/4 is a constrained method").
        for (text, option, says) in [
            ("svi:1/4", "points", "at least 2 nodes"),
            ("svi:300/4", "points", "at most 256"),
            ("svi:4/0", "quadrature", "at least 1 point"),
            ("svi:4/1000@nodes", "quadrature", "at most 256"),
            ("svi:0/0@nodes", "points", "at least 2 nodes"),
        ] {
            let error = text.parse::<SceneMethod>().unwrap_err();
            assert!(
                matches!(&error, svi::Error::InvalidParameter { name, .. } if *name == option),
                "{text}: {error:?}"
            );
            assert!(error.to_string().contains(says), "{text}: {error}");
        }
        assert!(matches!(
            "svi:4/3@nodes".parse::<SceneMethod>().unwrap(),
            SceneMethod::Constrained(_)
        ));
    }

    #[test]
    fn the_help_lists_every_constrained_method_of_the_registry() {
        let help = constrained_help();
        for name in ConstrainedMethod::names() {
            assert!(help.contains(&format!("\n  {name} ")), "{name}: {help}");
        }
        assert_eq!(help.lines().count(), ConstrainedMethod::names().len() + 1);
    }
}
