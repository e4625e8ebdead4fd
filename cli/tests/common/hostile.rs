//! What the hostile suites of the command line share (`hostile.rs`, `hostile_surfaces.rs`):
//! hostile values, the checks every case makes, and the counting runner.
#![allow(dead_code)] // each suite uses its own subset

use proptest::prelude::*;
use proptest::sample::select;
use proptest::test_runner::TestRunner;
use serde_json::Value;
use svi_experiments::{SceneError, Summary};

use super::common::has_long_number;
use super::hostile_cases::cases;

// ---- values ---------------------------------------------------------------------------------

/// A number as a user might type it, biased towards the hostile: NaN, ±∞, ±0, subnormals,
/// ±f64::MAX, 1e±300, integers beyond 2⁶⁴, and text that is no number at all.
pub fn hostile_number() -> BoxedStrategy<String> {
    prop_oneof![
        3 => select(vec![
            "nan", "NaN", "-nan", "inf", "-inf", "+inf", "infinity", "0", "-0", "0.0", "-1",
            "1e309", "-1e309", "1e300", "-1e300", "1e-300", "-1e-300", "5e-324", "-5e-324",
            "1.7976931348623157e308", "2.2250738585072014e-308", "18446744073709551616",
            "-9223372036854775809", "4294967296", "1e16", "1e-16", "0x10", "1_000", "", " ",
            "1e", "e5", "--1", "1..2", "one", "١", "1,5",
        ])
        .prop_map(String::from),
        2 => (-400i32..400).prop_map(|e| format!("1e{e}")),
        2 => any::<f64>().prop_map(|x| format!("{x:?}")),
        1 => any::<u64>().prop_map(|x| x.to_string()),
        1 => any::<i64>().prop_map(|x| x.to_string()),
    ]
    .boxed()
}

/// A number that no option may take as a value that makes a long run: NaN, ±∞, zero,
/// negatives, 1e±300 and beyond, integers beyond every cap, text. The binary's cases draw
/// from these (a valid tiny step would be a long run, not a hang).
pub fn rejected_number() -> BoxedStrategy<String> {
    prop_oneof![
        3 => select(vec![
            "nan", "NaN", "-nan", "inf", "-inf", "+inf", "infinity", "0", "-0", "0.0", "-1",
            "1e309", "-1e309", "1e300", "-1e300", "1e-300", "-1e-300", "5e-324", "-5e-324",
            "1.7976931348623157e308", "-1.7976931348623157e308", "18446744073709551616",
            "-9223372036854775809", "0x10", "1_000", "", " ", "1e", "e5", "--1", "1..2", "one",
            "١", "1,5",
        ])
        .prop_map(String::from),
        1 => (-1e300f64..-1e-300).prop_map(|x| format!("{x:?}")),
        1 => ((1u64 << 40)..u64::MAX).prop_map(|x| x.to_string()),
    ]
    .boxed()
}

/// Where a case runs: in process (any hostile number; runs are shortened by the test) or
/// the binary (numbers that must be rejected, and the cheap valid ones).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    InProcess,
    Binary,
}

impl Mode {
    /// Mostly one of `valid` (the values that keep a case short), else a hostile number.
    pub fn number_or(self, valid: &[&'static str]) -> BoxedStrategy<String> {
        prop_oneof![
            1 => select(valid.to_vec()).prop_map(String::from),
            1 => self.hostile(),
        ]
        .boxed()
    }

    /// The hostile numbers of the mode.
    pub fn hostile(self) -> BoxedStrategy<String> {
        match self {
            Mode::InProcess => hostile_number(),
            Mode::Binary => rejected_number(),
        }
    }
}

/// A TOML value: numbers of every kind, strings, arrays, garbage.
pub fn toml_value() -> BoxedStrategy<String> {
    prop_oneof![
        4 => (-1e3f64..1e3).prop_map(|x| format!("{x:?}")),
        2 => (-400i32..400).prop_map(|e| format!("1e{e}")),
        1 => select(vec![
            "nan", "inf", "-inf", "+inf", "0", "-0", "0.0", "-1", "1e309", "-1e309", "5e-324",
            "18446744073709551616", "-9223372036854775809", "\"6\"", "true", "[]", "[1.0]",
            "[1.0, 2.0, 3.0]", "{}", "\"\"", "0x10", "1_000", "--1", "1..2",
        ])
        .prop_map(String::from),
        1 => (0i64..100).prop_map(|x| x.to_string()),
        1 => "[a-z\\[\\]\"=.,0-9 -]{0,10}",
    ]
    .boxed()
}

/// Mostly a valid value from `valid`, sometimes a hostile one.
pub fn mostly(valid: impl Strategy<Value = String> + 'static) -> BoxedStrategy<String> {
    prop_oneof![4 => valid, 1 => toml_value()].boxed()
}

/// Mostly nothing, sometimes a few entries.
pub fn few<T: Clone + std::fmt::Debug + 'static>(
    entry: impl Strategy<Value = T> + 'static,
) -> BoxedStrategy<Vec<T>> {
    prop_oneof![2 => Just(Vec::new()), 1 => proptest::collection::vec(entry, 1..3)].boxed()
}

/// A flag and its value, or nothing (the flag left at its default).
pub fn flag(name: &'static str, value: BoxedStrategy<String>) -> BoxedStrategy<Vec<String>> {
    prop_oneof![
        1 => Just(Vec::new()),
        3 => value.prop_map(move |value| vec![name.to_string(), value]),
    ]
    .boxed()
}

// ---- checks shared by every test --------------------------------------------------------------

/// A rejection: a message, no number in 300 digits, and an option it blames is one the
/// arguments gave.
pub fn check_message(message: &str, args: &[String]) -> Result<(), TestCaseError> {
    prop_assert!(!message.trim().is_empty());
    prop_assert!(!message.contains("panicked"), "{}", message);
    prop_assert!(!has_long_number(message), "{:?}: {}", args, message);
    Ok(())
}

/// A rejection as a typed error: [`check_message`], and the option named by an error about
/// an option (`SceneError::InvalidOption`, `SceneError::NotApplicable`) was given, unless
/// it names a scene field too (the scene may have set it).
pub fn check_error(error: &SceneError, args: &[String]) -> Result<(), TestCaseError> {
    let message = error.to_string();
    check_message(&message, args)?;
    let option = match error {
        SceneError::InvalidOption { option, .. } | SceneError::NotApplicable { option, .. } => {
            Some(*option)
        }
        _ => None,
    };
    if let Some(option) = option {
        // "--t-end (run.t_end)", "--diagnostics momentum (output.diagnostics)": the flag.
        // An option that names a scene field, "(run.recovery)", may come from the scene.
        let flag = option.split([' ', ':']).next().unwrap_or(option);
        if flag.starts_with("--") && !option.contains('(') {
            prop_assert!(
                args.iter()
                    .any(|arg| arg == flag || arg.starts_with(&format!("{flag}="))),
                "{:?}: blames {} — {}",
                args,
                flag,
                message
            );
        }
    }
    Ok(())
}

/// The JSON fields of a summary that are numbers in every run (a NaN would print as null).
pub const FINITE_FIELDS: [&str; 7] = [
    "h",
    "t0",
    "t_end",
    "energy_initial",
    "energy_final",
    "energy_scale",
    "seconds",
];

/// The JSON array fields of a final state, on ℝᴺ, on SO(3) and on the other Lie groups.
pub const STATE_FIELDS: [&str; 10] = [
    "q",
    "v",
    "p",
    "attitude",
    "quaternion",
    "omega",
    "g",
    "xi",
    "momentum",
    "spatial_momentum",
];

/// A successful run's JSON: every number of the state and the energies is finite (serde
/// prints NaN and ±∞ as null), every diagnostic is a finite number or null (not asked for),
/// and every output point's state too.
pub fn check_summary_json(json: &Value, context: &str) -> Result<(), TestCaseError> {
    let finite = |value: &Value| value.as_f64().is_some_and(f64::is_finite);
    for field in FINITE_FIELDS {
        prop_assert!(
            finite(&json[field]),
            "{}: {} = {}",
            context,
            field,
            json[field]
        );
    }
    let states = std::iter::once(json).chain(
        json["outputs"]
            .as_array()
            .map(|outputs| outputs.iter())
            .into_iter()
            .flatten(),
    );
    for state in states {
        let mut fields = 0;
        for field in STATE_FIELDS {
            if let Some(values) = state[field].as_array() {
                fields += 1;
                prop_assert!(
                    values.iter().all(finite),
                    "{}: {} = {}",
                    context,
                    field,
                    state
                );
            }
        }
        prop_assert!(fields >= 3, "{}: no state in {}", context, state);
    }
    // An O(1) energy error of a model that conserves energy never passes unwarned.
    let model = json["model"].as_str().unwrap_or_default();
    if json["status"] == "ok" && conserves_energy(model) {
        let error = json["energy_error_max"].as_f64().unwrap_or_else(|| {
            (json["energy_final"].as_f64().unwrap_or(f64::NAN)
                - json["energy_initial"].as_f64().unwrap_or(f64::NAN))
            .abs()
        });
        let scale = json["energy_scale"].as_f64().unwrap_or(f64::NAN);
        let warned = json["warnings"]
            .as_array()
            .is_some_and(|warnings| warnings.iter().any(|w| w["kind"] == "energy"));
        prop_assert!(
            warned || error <= scale,
            "{}: energy error {} against the scale {} without a warning",
            context,
            error,
            scale
        );
    }
    for (key, value) in json.as_object().into_iter().flatten() {
        if key.ends_with("_max") || key.ends_with("_relative") || key.ends_with("_final") {
            prop_assert!(
                value.is_null() || finite(value),
                "{}: {} = {}",
                context,
                key,
                value
            );
        }
    }
    Ok(())
}

/// Whether the named model conserves energy: a model on a Lie group (none is forced), or a
/// model on ℝᴺ that is neither forced nor time-dependent.
pub fn conserves_energy(model: &str) -> bool {
    struct Conserves;
    impl svi_models::ModelVisitor for Conserves {
        type Output = bool;
        fn visit<M: svi_models::ZooModel<N>, N: svi::Dimension>(self, _: M) -> bool
        where
            nalgebra::DefaultAllocator:
                nalgebra::allocator::Allocator<N> + nalgebra::allocator::Allocator<N, N>,
        {
            !M::FORCED && !M::TIME_DEPENDENT
        }
    }
    svi_models::RIGID_MODEL_NAMES.contains(&model)
        || svi_models::GROUP_MODEL_NAMES.contains(&model)
        || svi_models::visit_model(model, Conserves).unwrap_or(false)
}

/// A successful run in process: [`check_summary_json`] on its JSON, as `svi run --json`
/// prints it.
pub fn check_summary(summary: &Summary, context: &str) -> Result<(), TestCaseError> {
    let json = serde_json::to_value(summary).map_err(|e| TestCaseError::fail(e.to_string()))?;
    check_summary_json(&json, context)
}

/// Run `runner` over `strategy` with `base` cases (times `SVI_HOSTILE_CASES`), counting
/// the outcomes `test` reports by index; print the counts and return them.
pub fn run_counting<S: Strategy>(
    name: &str,
    base: u32,
    labels: &[&str],
    strategy: S,
    test: impl Fn(S::Value) -> Result<usize, TestCaseError>,
) -> Vec<usize> {
    run_counting_stream(name, 0, base, labels, strategy, test)
}

/// [`run_counting`] on the `stream`-th sequence of cases of a fixed seed (the seed plus
/// `stream`): a long search split into tests that run in parallel, each drawing other cases.
pub fn run_counting_stream<S: Strategy>(
    name: &str,
    stream: u64,
    base: u32,
    labels: &[&str],
    strategy: S,
    test: impl Fn(S::Value) -> Result<usize, TestCaseError>,
) -> Vec<usize> {
    let mut config = cases(base);
    if let proptest::test_runner::RngSeed::Fixed(seed) = config.rng_seed {
        config.rng_seed = proptest::test_runner::RngSeed::Fixed(seed.wrapping_add(stream));
    }
    let total = config.cases as usize;
    let counts = std::cell::RefCell::new(vec![0usize; labels.len()]);
    TestRunner::new(config)
        .run(&strategy, |value| {
            let outcome = test(value)?;
            counts.borrow_mut()[outcome] += 1;
            Ok(())
        })
        .unwrap();
    let counts = counts.into_inner();
    let described: Vec<String> = labels
        .iter()
        .zip(&counts)
        .map(|(label, count)| format!("{count} {label}"))
        .collect();
    eprintln!("{name}: {total} inputs: {}", described.join(", "));
    assert_eq!(counts.iter().sum::<usize>(), total);
    counts
}
