//! Helpers shared by the `svi` binary's test files: run the binary, parse its JSON, check
//! its failures, and scratch directories.
#![allow(dead_code)] // each test file uses its own subset

use std::path::PathBuf;
use std::process::{Command, Output};

use serde_json::Value;

/// Run `svi` with `args`.
pub fn svi(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_svi"))
        .args(args)
        .output()
        .expect("the svi binary runs")
}

/// Run `svi` with `args`, expect success, and parse stdout as JSON.
pub fn json(args: &[&str]) -> Value {
    let output = svi(args);
    assert!(
        output.status.success(),
        "svi {args:?} failed: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    serde_json::from_slice(&output.stdout).expect("stdout is one JSON object")
}

/// Run `svi` with `args`, expect failure (not a panic), and return stderr.
pub fn failure(args: &[&str]) -> String {
    let output = svi(args);
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    assert!(!output.status.success(), "svi {args:?} succeeded");
    assert!(output.stdout.is_empty(), "svi {args:?} printed to stdout");
    assert!(
        !stderr.contains("panicked"),
        "svi {args:?} panicked: {stderr}"
    );
    assert!(stderr.contains("error"), "svi {args:?}: {stderr}");
    stderr
}

/// Run `svi` with `command` followed by `args`, expect exit status 2 (bad input, as for
/// malformed arguments) and `needle` in the message; return stderr.
pub fn bad_input(command: &[&str], args: &[&str], needle: &str) -> String {
    let all: Vec<&str> = command.iter().chain(args).copied().collect();
    let stderr = failure(&all);
    assert!(stderr.contains(needle), "svi {all:?}: {stderr}");
    assert_eq!(svi(&all).status.code(), Some(2), "svi {all:?}: {stderr}");
    stderr
}

/// A scene file in its own scratch directory.
pub struct SceneFile {
    /// The file.
    pub path: String,
    _dir: Scratch,
}

/// Write a scene file.
pub fn scene_file(name: &str, text: &str) -> SceneFile {
    let dir = Scratch::new(name);
    let path = dir.join("scene.toml");
    std::fs::write(&path, text).unwrap();
    SceneFile {
        path: path.to_str().unwrap().to_owned(),
        _dir: dir,
    }
}

/// The number `value[key]`.
pub fn number(value: &Value, key: &str) -> f64 {
    value[key]
        .as_f64()
        .unwrap_or_else(|| panic!("{key} is not a number: {value}"))
}

/// The array of numbers `value[key]`.
pub fn vector(value: &Value, key: &str) -> Vec<f64> {
    value[key]
        .as_array()
        .unwrap_or_else(|| panic!("{key} is not an array: {value}"))
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

/// A fresh scratch directory for this test process, removed when dropped.
pub struct Scratch(pub PathBuf);

impl Scratch {
    /// The directory `svi-cli-test-<pid>-<name>` under the system's temporary directory.
    pub fn new(name: &str) -> Scratch {
        let dir = std::env::temp_dir().join(format!("svi-cli-test-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        Scratch(dir)
    }

    /// A path inside the directory.
    pub fn join(&self, file: &str) -> PathBuf {
        self.0.join(file)
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}
