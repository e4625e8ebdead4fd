//! Helpers shared by the `svi` binary's test files: run the binary, parse its JSON, check
//! its failures, and scratch directories.
#![allow(dead_code)] // each test file uses its own subset

use std::collections::HashMap;
use std::io::Read;
use std::path::PathBuf;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use serde_json::Value;

/// Run `svi` with `args`.
pub fn svi(args: &[&str]) -> Output {
    let output = Command::new(env!("CARGO_BIN_EXE_svi"))
        .args(args)
        .output()
        .expect("the svi binary runs");
    keep_json(args, &output);
    output
}

/// With `SVI_JSON_OUTPUTS` set to a directory, keep the standard output of every command with
/// `--json` there, one file per command (its arguments and its output), for
/// `python/tests/test_schema.py` to validate against `docs/schema/result.schema.json`: every
/// `--json` output of the tests, success and failure, every kind of scene.
fn keep_json(args: &[&str], output: &Output) {
    static KEPT: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let Some(dir) = std::env::var_os("SVI_JSON_OUTPUTS") else {
        return;
    };
    if !args.contains(&"--json") {
        return;
    }
    let index = KEPT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let record = serde_json::json!({
        "args": args,
        "status": output.status.code(),
        "stdout": String::from_utf8_lossy(&output.stdout),
    });
    let dir = PathBuf::from(dir);
    let path = dir.join(format!("{}-{index}.json", std::process::id()));
    std::fs::create_dir_all(&dir)
        .and_then(|()| std::fs::write(&path, record.to_string()))
        .unwrap_or_else(|error| {
            panic!("cannot keep a --json output in {}: {error}", path.display())
        });
}

/// Run `svi` with `args` and no input; kill it if it runs longer than `limit` (an error
/// saying so: a hang, or a run far longer than the input asked for).
pub fn svi_within(args: &[&str], limit: Duration) -> Result<Output, String> {
    svi_within_in(None, args, limit)
}

/// [`svi_within`] in the working directory `dir` (where relative output paths go).
pub fn svi_within_in(
    dir: Option<&std::path::Path>,
    args: &[&str],
    limit: Duration,
) -> Result<Output, String> {
    let mut command = Command::new(env!("CARGO_BIN_EXE_svi"));
    if let Some(dir) = dir {
        command.current_dir(dir);
    }
    let mut child = command
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|error| format!("svi {args:?} does not start: {error}"))?;
    // Drain both pipes as the child writes, so that it never blocks on a full pipe.
    let drain = |pipe: Option<Box<dyn Read + Send>>| {
        std::thread::spawn(move || {
            let mut bytes = Vec::new();
            if let Some(mut pipe) = pipe {
                let _ = pipe.read_to_end(&mut bytes);
            }
            bytes
        })
    };
    let stdout = drain(
        child
            .stdout
            .take()
            .map(|p| Box::new(p) as Box<dyn Read + Send>),
    );
    let stderr = drain(
        child
            .stderr
            .take()
            .map(|p| Box::new(p) as Box<dyn Read + Send>),
    );
    let start = Instant::now();
    let mut pause = Duration::from_millis(1);
    let status = loop {
        if let Some(status) = child.try_wait().map_err(|error| error.to_string())? {
            break status;
        }
        if start.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            return Err(format!(
                "svi {args:?} ran longer than {limit:?} and was killed"
            ));
        }
        std::thread::sleep(pause);
        pause = (pause * 2).min(Duration::from_millis(20));
    };
    let output = Output {
        status,
        stdout: stdout.join().unwrap_or_default(),
        stderr: stderr.join().unwrap_or_default(),
    };
    keep_json(args, &output);
    Ok(output)
}

/// The time any single command of the tests may take before it counts as a hang: far
/// above what each one needs (well under a second), so that a loaded CI machine does not
/// trip it.
pub const HANG: Duration = Duration::from_secs(60);

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

/// Run `svi` with `command` followed by `args` (killed after [`HANG`]), expect exit status
/// 2 (bad input, as for malformed arguments), no panic, nothing on stdout and `needle` in
/// the message; return stderr.
pub fn bad_input(command: &[&str], args: &[&str], needle: &str) -> String {
    let all: Vec<&str> = command.iter().chain(args).copied().collect();
    let output = svi_within(&all, HANG).unwrap_or_else(|hang| panic!("{hang}"));
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    assert_eq!(output.status.code(), Some(2), "svi {all:?}: {stderr}");
    assert!(output.stdout.is_empty(), "svi {all:?} printed to stdout");
    assert!(
        !stderr.contains("panicked"),
        "svi {all:?} panicked: {stderr}"
    );
    assert!(stderr.starts_with("error: "), "svi {all:?}: {stderr}");
    assert!(stderr.contains(needle), "svi {all:?}: {stderr}");
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

/// Whether `text` holds a run of 22 or more digits: a number printed in full (`{}` of 1e300
/// or 1e-300) where it should read 1e300. Shortest round-trip numbers have at most 17
/// significant digits, and integers up to 2⁶⁴ at most 20.
pub fn has_long_number(text: &str) -> bool {
    let mut run = 0;
    for c in text.chars() {
        run = if c.is_ascii_digit() { run + 1 } else { 0 };
        if run >= 22 {
            return true;
        }
    }
    false
}

/// Parse a CSV table (`svi ensemble`'s, `svi bench`'s) into rows by column name (quoted
/// fields only at the end of a row: the error message).
pub fn parse_csv(text: &str) -> Vec<HashMap<String, String>> {
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    lines
        .map(|line| {
            let (plain, quoted) = match line.find('"') {
                Some(at) => (
                    &line[..at],
                    Some(line[at..].trim_matches('"').replace("\"\"", "\"")),
                ),
                None => (line, None),
            };
            let mut fields: Vec<String> = plain.split(',').map(String::from).collect();
            if let Some(quoted) = quoted {
                fields.pop();
                fields.push(quoted);
            }
            assert_eq!(fields.len(), header.len(), "{line}");
            header.iter().map(|h| h.to_string()).zip(fields).collect()
        })
        .collect()
}

/// The number in a cell.
pub fn cell(row: &HashMap<String, String>, column: &str) -> f64 {
    row[column]
        .parse()
        .unwrap_or_else(|_| panic!("{column} = '{}' is not a number", row[column]))
}

/// The numbers of the field `key` of a JSON object, read from its text with Rust's exact
/// parser (serde_json's own float parsing may be off in the last digit): the first occurrence
/// of `"key":`, a number or an array of numbers.
pub fn raw(text: &str, key: &str) -> Vec<f64> {
    let pattern = format!("\"{key}\":");
    let start = text
        .find(&pattern)
        .unwrap_or_else(|| panic!("no {key} in {text}"))
        + pattern.len();
    let rest = &text[start..];
    let token = if let Some(array) = rest.strip_prefix('[') {
        &array[..array.find(']').unwrap()]
    } else {
        &rest[..rest.find([',', '}']).unwrap()]
    };
    token.split(',').map(|x| x.parse().unwrap()).collect()
}
