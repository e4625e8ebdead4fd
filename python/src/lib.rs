//! `svi._svi`: the native module of the svi Python package.
//!
//! Every function calls `svi_experiments`, the library behind the command line: a run is
//! [`Scene::open`], the `[initial]` fields, [`Scene::overlay`] of the overrides, then
//! [`Scene::run`] (which checks the scene, once) — the path of `svi run` — so
//! `svi.run("kepler")` and `svi run kepler --json` print the same numbers. Results cross into Python as JSON text (a summary, a failure) and
//! lists of numbers (trajectories, tables); `svi/__init__.py` turns them into NumPy arrays,
//! result objects, exceptions and DataFrames. The Global Interpreter Lock is released while
//! Rust runs, on a worker thread, while the calling thread looks for signals: Ctrl-C stops a
//! run or an ensemble between steps and raises `KeyboardInterrupt` ([`interruptible`]).
//!
//! A failure raises `svi._svi.Failure` with one argument, the JSON text of the failure object
//! of `svi run --json` (`kind`, `message`, `step`, `t`) plus `bad_input` and `summary` (the
//! run up to its last good state, for a run that failed after it started).

use std::collections::BTreeMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, RecvTimeoutError};
use std::time::Duration;

use numpy::{PyArray1, PyReadonlyArray1};
use pyo3::create_exception;
use pyo3::exceptions::{PyException, PyTypeError};
use pyo3::prelude::*;
use svi::model::rhs::HamiltonianRhs;
use svi::stepping::dense::DenseOutput;
use svi_experiments::ensemble::Ensemble;
use svi_experiments::report::schema;
use svi_experiments::report::table::Cell;
use svi_experiments::run::{LossAt, error_report};
use svi_experiments::scene::ensemble::{Random, parse_initial_axis, parse_parameter_axis};
use svi_experiments::scene::events::NativeEvent;
use svi_experiments::scene::field::FieldScene;
use svi_experiments::scene::overrides::{OptionKind, OptionValue};
use svi_experiments::scene::spectral::SpectralScene;
use svi_experiments::{Components, Control, Overrides, Scene, SceneError};

create_exception!(
    _svi,
    Failure,
    PyException,
    "A failed call: its one argument is the JSON text of the failure object."
);

/// The Python exception of a scene error: its JSON failure object.
fn failure(error: SceneError) -> PyErr {
    let bad_input = error.is_bad_input();
    let report = error_report(&error);
    let summary = match &error {
        SceneError::RunFailed { partial, .. } => schema::to_value(partial.as_ref()).ok(),
        _ => None,
    };
    let object = serde_json::json!({
        "kind": report.kind,
        "message": format!("{}", DisplayChain(&error)),
        "step": report.step,
        "t": report.t,
        "bad_input": bad_input,
        "summary": summary,
    });
    Failure::new_err(object.to_string())
}

/// An error with its sources, `a: b: c`, as `svi` prints it.
struct DisplayChain<'a>(&'a (dyn std::error::Error + 'static));

impl std::fmt::Display for DisplayChain<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.0)?;
        let mut source = self.0.source();
        while let Some(cause) = source {
            write!(f, ": {cause}")?;
            source = cause.source();
        }
        Ok(())
    }
}

/// A bad argument value, as the failure of an invalid option.
fn invalid(option: &'static str, reason: String) -> PyErr {
    failure(SceneError::InvalidOption { option, reason })
}

/// The options of `svi run` that are not keywords of the package's calls: the model's
/// parameters are the `params` dict, files are not written (results come back as arrays), and
/// the trajectory's thinning is `every` of the trajectory; the events come in the summary.
const NOT_KEYWORDS: [&str; 5] = ["parameters", "out", "plot", "every", "events_out"];

/// A keyword argument's value, of the kinds of [`OptionKind`] (the package checked it).
#[derive(FromPyObject)]
enum Value {
    /// First: a Python bool is an int too, and only a bool is a flag.
    Flag(bool),
    Count(u64),
    Real(f64),
    Text(String),
    Reals(Vec<f64>),
    Names(Vec<String>),
}

/// The options of `svi run` the package's calls take as keywords, each with the kind of its
/// value (`real`, `count`, `text`, `reals`, `names`, `flag`): `Overrides` is their one definition, so
/// a flag added to `svi run` is a keyword of `svi.run`, `svi.solve` and `svi.ensemble`.
#[pyfunction]
fn options() -> Vec<(String, &'static str)> {
    Overrides::options()
        .into_iter()
        .filter(|(name, _)| !NOT_KEYWORDS.contains(&name.as_str()))
        .map(|(name, kind)| (name, kind.name()))
        .collect()
}

/// The overrides of keyword `options` (see [`options`]) and the model's `params`.
fn overrides(
    options: Option<BTreeMap<String, Value>>,
    params: Option<BTreeMap<String, f64>>,
) -> PyResult<Overrides> {
    let kinds: BTreeMap<String, OptionKind> = Overrides::options().into_iter().collect();
    let named: Vec<(String, OptionValue)> = options
        .unwrap_or_default()
        .into_iter()
        .map(|(name, value)| {
            let value = match value {
                Value::Count(n) => OptionValue::Count(n),
                Value::Real(x) => OptionValue::Real(x),
                Value::Text(text) => OptionValue::Text(text),
                Value::Reals(xs) => OptionValue::Reals(xs),
                Value::Names(texts) if kinds.get(&name) == Some(&OptionKind::Texts) => {
                    OptionValue::Texts(texts)
                }
                Value::Names(names) => OptionValue::Names(names),
                Value::Flag(flag) => OptionValue::Flag(flag),
            };
            (name, value)
        })
        .collect();
    if let Some((name, _)) = named
        .iter()
        .find(|(name, _)| NOT_KEYWORDS.contains(&name.as_str()))
    {
        return Err(invalid(
            "option",
            format!("'{name}' is not an option of this call"),
        ));
    }
    let mut overrides = Overrides::from_named(&named).map_err(failure)?;
    overrides.parameters = params.unwrap_or_default().into_iter().collect();
    Ok(overrides)
}

/// Put the fields of `initial` (`t0`, `q`, `v`, `p`, `rotation`, `quaternion`, `omega`,
/// `momentum`, `g`, `log`, `xi`) into the scene's `[initial]` (a velocity replaces the scene's momentum and so
/// on); the run checks the scene.
fn set_initial(scene: &mut Scene, initial: BTreeMap<String, Vec<f64>>) -> PyResult<()> {
    // A field given replaces the scene's exclusive partner (v for p, omega for momentum, ...)
    // unless both are given, which the scene's check rejects.
    let section = &mut scene.initial;
    for (given, partner) in [("v", &mut section.p), ("p", &mut section.v)] {
        if initial.contains_key(given) {
            *partner = None;
        }
    }
    let clear = |slot: &mut Option<Vec<f64>>, given: &[&str]| {
        if given.iter().any(|name| initial.contains_key(*name)) {
            *slot = None;
        }
    };
    clear(&mut section.quaternion, &["rotation"]);
    clear(&mut section.rotation, &["quaternion"]);
    clear(&mut section.momentum, &["omega", "xi"]);
    clear(&mut section.omega, &["momentum"]);
    clear(&mut section.xi, &["momentum"]);
    clear(&mut section.log, &["g"]);
    clear(&mut section.g, &["log"]);
    for (name, values) in initial {
        let section = &mut scene.initial;
        let slot = match name.as_str() {
            "t0" => {
                let [t0] = values.as_slice() else {
                    return Err(invalid("initial", "t0 is one number".into()));
                };
                section.t0 = Some(*t0);
                continue;
            }
            "q" | "v" | "p" => {
                let vector = match name.as_str() {
                    "q" => &mut section.q,
                    "v" => &mut section.v,
                    _ => &mut section.p,
                };
                *vector = Some(Components::Values(values));
                continue;
            }
            "rotation" => &mut section.rotation,
            "quaternion" => &mut section.quaternion,
            "omega" => &mut section.omega,
            "momentum" => &mut section.momentum,
            "g" => &mut section.g,
            "log" => &mut section.log,
            "xi" => &mut section.xi,
            other => {
                return Err(invalid(
                    "initial",
                    format!(
                        "unknown field '{other}' (known: t0, q, v, p, rotation, quaternion, \
                         omega, momentum, g, log, xi)"
                    ),
                ));
            }
        };
        *slot = Some(values);
    }
    Ok(())
}

/// Put `initial` into the scene's `[initial]` ([`set_initial`]) and lay `overrides` over it:
/// a scene as `svi run` with these flags has it.
fn configure(
    scene: &mut Scene,
    initial: Option<BTreeMap<String, Vec<f64>>>,
    overrides: &Overrides,
) -> PyResult<()> {
    if let Some(initial) = initial {
        set_initial(scene, initial)?;
    }
    scene.overlay(overrides).map_err(failure)
}

/// How often the calling thread looks for signals while a run goes on.
const SIGNAL_PERIOD: Duration = Duration::from_millis(50);

/// Run `work` on a worker thread with the GIL released while this thread looks for signals
/// every [`SIGNAL_PERIOD`]: the exception of a signal's handler (`KeyboardInterrupt` for
/// Ctrl-C) sets the stop flag `work` is given, waits for `work` to stop (between steps) and
/// is raised. A signal handler runs on the main thread only, hence the worker.
fn interruptible<T: Send>(
    py: Python<'_>,
    work: impl FnOnce(&AtomicBool) -> T + Send,
) -> PyResult<T> {
    let stop = AtomicBool::new(false);
    let (result, signal) = py.detach(|| {
        std::thread::scope(|scope| {
            let (sender, receiver) = mpsc::channel();
            let flag = &stop;
            let worker = scope.spawn(move || {
                // The receiver lives until the result arrives.
                let _ = sender.send(work(flag));
            });
            let mut signal = None;
            loop {
                match receiver.recv_timeout(SIGNAL_PERIOD) {
                    Ok(result) => return (result, signal),
                    Err(RecvTimeoutError::Timeout) if signal.is_none() => {
                        if let Err(error) = Python::attach(|py| py.check_signals()) {
                            stop.store(true, Ordering::Relaxed);
                            signal = Some(error);
                        }
                    }
                    Err(RecvTimeoutError::Timeout) => {}
                    // The worker panicked: its panic goes on here.
                    Err(RecvTimeoutError::Disconnected) => match worker.join() {
                        Err(panic) => std::panic::resume_unwind(panic),
                        Ok(()) => unreachable!("a worker that returned sent its result"),
                    },
                }
            }
        })
    });
    match signal {
        Some(error) => Err(error),
        None => Ok(result),
    }
}

/// `values` as a NumPy array that owns them: arrays cross into Python without a copy, not as
/// lists of Python floats.
fn array(py: Python<'_>, values: Vec<f64>) -> Bound<'_, PyArray1<f64>> {
    PyArray1::from_vec(py, values)
}

/// A trajectory: its column names and its numbers row by row.
type Trajectory<'py> = (Vec<String>, Bound<'py, PyArray1<f64>>);

/// An event given as a Python callable: (name, direction, terminal, g) with g(t, q, v) of a
/// float and two NumPy arrays.
type CallableEvent = (String, String, bool, Py<PyAny>);

/// The Python exception raised by an event's callable during a run, kept until the run ends.
type Raised = std::sync::Arc<std::sync::Mutex<Option<PyErr>>>;

/// The scene events of `callables`, each calling its Python function with the GIL held; an
/// exception the function raises (or a result that is not a float) is kept in `raised` and
/// the event's value is NaN, which fails the run naming the event.
fn native_events(callables: Vec<CallableEvent>, raised: &Raised) -> PyResult<Vec<NativeEvent>> {
    callables
        .into_iter()
        .map(|(name, direction, terminal, function)| {
            let direction = direction
                .parse()
                .map_err(|error: svi::Error| invalid("event", error.to_string()))?;
            let raised = std::sync::Arc::clone(raised);
            let event = name.clone();
            let call = move |t: f64, q: &[f64], v: &[f64]| -> f64 {
                Python::attach(|py| {
                    let value = function
                        .call1(
                            py,
                            (t, PyArray1::from_slice(py, q), PyArray1::from_slice(py, v)),
                        )
                        .and_then(|value| {
                            value.extract::<f64>(py).map_err(|_| {
                                let kind = value.bind(py).get_type().name().map_or_else(
                                    |_| "another type".to_string(),
                                    |name| name.to_string(),
                                );
                                PyTypeError::new_err(format!(
                                    "event '{event}': g(t, q, v) returned {kind}, not a float"
                                ))
                            })
                        });
                    value.unwrap_or_else(|error| {
                        let mut kept = raised.lock().unwrap_or_else(|e| e.into_inner());
                        kept.get_or_insert(error);
                        f64::NAN
                    })
                })
            };
            Ok(NativeEvent {
                name,
                direction,
                terminal,
                function: std::sync::Arc::new(call),
            })
        })
        .collect()
}

/// A model written as text from Python (`svi.Lagrangian`, `svi.Hamiltonian`): what it is
/// written as (`"lagrangian"` or `"hamiltonian"`), L or H, its coordinates, its forces, the
/// generators of its symmetries, its holonomic constraints and its parameters.
type TextModel = (
    String,
    String,
    Vec<String>,
    Option<Vec<String>>,
    Option<Vec<Vec<String>>>,
    Option<Vec<String>>,
    BTreeMap<String, f64>,
);

/// Every step's polynomial of a run (`svi.Solution`'s dense output), evaluated from Python.
#[pyclass(frozen, module = "svi._svi")]
struct Dense(DenseOutput);

#[pymethods]
impl Dense {
    /// (q, v, p) at `times`, each an array of len(times) × dimension numbers, row by row.
    fn evaluate<'py>(
        &self,
        py: Python<'py>,
        times: PyReadonlyArray1<'py, f64>,
    ) -> PyResult<[Bound<'py, PyArray1<f64>>; 3]> {
        let n = self.0.dimension();
        let times = times.as_slice()?;
        let count = times.len();
        let [mut q, mut v, mut p] = [
            vec![0.0; count * n],
            vec![0.0; count * n],
            vec![0.0; count * n],
        ];
        for (i, &time) in times.iter().enumerate() {
            let rows = i * n..(i + 1) * n;
            self.0
                .evaluate(
                    time,
                    &mut q[rows.clone()],
                    &mut v[rows.clone()],
                    &mut p[rows],
                )
                .map_err(|error| failure(SceneError::from(error)))?;
        }
        Ok([array(py, q), array(py, v), array(py, p)])
    }

    /// The span of the steps kept: (first step's start, last step's end).
    fn span(&self) -> Option<(f64, f64)> {
        self.0.span()
    }

    /// The number of coordinates.
    fn dimension(&self) -> usize {
        self.0.dimension()
    }
}

/// Run a scene as `svi run` does, with these overrides; returns the JSON summary, with
/// `trajectory` the trajectory's column names and numbers (every step, or the output times),
/// and with `dense` every step's polynomial. `model` (a text model from `svi.Lagrangian`)
/// replaces `scene`. `progress` allows `svi run`'s progress bar on stderr (long fixed-step
/// runs, on a terminal). `events` are events given as Python callables ([`CallableEvent`]):
/// an exception one raises is raised again when the run ends.
#[pyfunction]
#[pyo3(signature = (
    scene, *, model=None, params=None, initial=None, options=None, trajectory=true, every=None,
    progress=false, dense=false, events=vec![]
))]
#[allow(clippy::too_many_arguments)]
fn run<'py>(
    py: Python<'py>,
    scene: &str,
    model: Option<TextModel>,
    params: Option<BTreeMap<String, f64>>,
    initial: Option<BTreeMap<String, Vec<f64>>>,
    options: Option<BTreeMap<String, Value>>,
    trajectory: bool,
    every: Option<usize>,
    progress: bool,
    dense: bool,
    events: Vec<CallableEvent>,
) -> PyResult<(String, Option<Trajectory<'py>>, Option<Dense>)> {
    let overrides = overrides(options, params)?;
    let mut loaded = match model {
        Some((kind, expression, coordinates, forces, symmetries, constraints, parameters)) => {
            let hamiltonian = kind == "hamiltonian";
            Scene::of_text_model(
                (!hamiltonian).then(|| expression.clone()),
                hamiltonian.then_some(expression),
                coordinates,
                forces,
                symmetries,
                constraints,
                parameters,
            )
        }
        None => load(scene)?,
    };
    configure(&mut loaded, initial, &overrides)?;
    let raised = Raised::default();
    loaded.native_events = native_events(events, &raised)?;
    // The trajectory is the rows the run path writes, kept in memory: no file is written.
    loaded.output.trajectory = None;
    loaded.output.plot = None;
    loaded.output.record = trajectory;
    loaded.output.every = every;
    loaded.output.dense = dense;
    let result = interruptible(py, |stop| {
        loaded.run(Control {
            progress,
            stop: Some(stop),
        })
    })?;
    if let Some(error) = raised.lock().unwrap_or_else(|e| e.into_inner()).take() {
        return Err(error);
    }
    let mut summary = result.map_err(failure)?;
    let rows = summary
        .recorded
        .take()
        .map(|recorded| (recorded.columns, array(py, recorded.values)));
    let dense = summary.dense.take().map(Dense);
    summary.trajectory = None;
    let json = schema::to_json(&summary).map_err(|error| invalid("summary", error.to_string()))?;
    Ok((json, rows, dense))
}

/// The gradient of a loss over a scene's fixed-step run (`svi.gradient`), by the discrete
/// adjoint ([`Scene::gradient`]): with respect to the `sensitivity` names of `options`, at the
/// outputs of its `sensitivity_every`. `loss(j, t, q, v)` returns (ℓ_j, ∂ℓ_j/∂q, ∂ℓ_j/∂v) as a
/// float and two lists (the package checks what the user's function returns); an exception it
/// raises is raised again when the gradient ends. Returns the gradient's JSON.
#[pyfunction]
#[pyo3(signature = (scene, loss, *, params=None, initial=None, options=None, checkpoints=None))]
fn gradient(
    py: Python<'_>,
    scene: &str,
    loss: Py<PyAny>,
    params: Option<BTreeMap<String, f64>>,
    initial: Option<BTreeMap<String, Vec<f64>>>,
    options: Option<BTreeMap<String, Value>>,
    checkpoints: Option<usize>,
) -> PyResult<String> {
    let mut loaded = load(scene)?;
    configure(&mut loaded, initial, &overrides(options, params)?)?;
    let raised = Raised::default();
    let kept = std::sync::Arc::clone(&raised);
    // An exception is kept and the output's loss is NaN, which fails the gradient.
    let call = move |j: usize, t: f64, q: &[f64], v: &[f64]| -> LossAt {
        Python::attach(|py| {
            loss.call1(
                py,
                (
                    j,
                    t,
                    PyArray1::from_slice(py, q),
                    PyArray1::from_slice(py, v),
                ),
            )
            .and_then(|value| value.extract::<LossAt>(py))
            .unwrap_or_else(|error| {
                let mut kept = kept.lock().unwrap_or_else(|e| e.into_inner());
                kept.get_or_insert(error);
                (f64::NAN, Vec::new(), Vec::new())
            })
        })
    };
    let result = interruptible(py, |_stop| loaded.gradient(&call, checkpoints))?;
    if let Some(error) = raised.lock().unwrap_or_else(|e| e.into_inner()).take() {
        return Err(error);
    }
    let summary = result.map_err(failure)?;
    serde_json::to_string(&summary).map_err(|error| invalid("gradient", error.to_string()))
}

/// The scene `name`: a built-in scene or an existing scene file (as `svi run` loads it), else
/// the text of a scene (TOML: it has a line break or `=`), else a zoo model with its
/// defaults. A field or pseudospectral scene is named as such: the package runs the ODE
/// scenes and those on Lie groups.
fn load(name: &str) -> PyResult<Scene> {
    let is_file = std::path::Path::new(name).is_file();
    if !is_file && name.contains(['\n', '=']) {
        return Scene::parse(name, "a scene text").map_err(failure);
    }
    if FieldScene::load(name).is_some() || SpectralScene::load(name).is_some() {
        return Err(failure(SceneError::NotApplicable {
            option: "scene",
            reason: format!(
                "'{name}' is a field or pseudospectral scene; the Python package runs the ODE \
                 scenes and those on Lie groups (run it with `svi run {name}`)"
            ),
        }));
    }
    match Scene::open(name) {
        Err(SceneError::UnknownScene { .. })
            if svi_models::MODEL_NAMES.contains(&name)
                || svi_models::LOCAL_MODEL_NAMES.contains(&name)
                || svi_models::RIGID_MODEL_NAMES.contains(&name)
                || svi_models::GROUP_MODEL_NAMES.contains(&name) =>
        {
            Scene::parse(&format!("model = \"{name}\"\n"), "a model name").map_err(failure)
        }
        result => result.map_err(failure),
    }
}

/// An ensemble's table chunk: (total members, column names, rows).
type Chunk = (usize, Vec<String>, Vec<Vec<Py<PyAny>>>);

/// Run the members `start..stop` of an ensemble (all without `stop`; none with `stop =
/// start`) as `svi ensemble` does, on `threads` threads (0: every core); returns the number
/// of members, the table's columns and the rows of those members. `model` (a text model from
/// `svi.Lagrangian`) replaces `scene`; `base` holds initial-state fields every member starts
/// from before its varied components.
#[pyfunction]
#[pyo3(signature = (
    scene, *, model=None, base=None, params=vec![], initial=vec![], random=None, seed=0, start=0,
    stop=None, threads=0, options=None
))]
#[allow(clippy::too_many_arguments)]
fn ensemble(
    py: Python<'_>,
    scene: &str,
    model: Option<TextModel>,
    base: Option<BTreeMap<String, Vec<f64>>>,
    params: Vec<String>,
    initial: Vec<String>,
    random: Option<usize>,
    seed: u64,
    start: usize,
    stop: Option<usize>,
    threads: usize,
    options: Option<BTreeMap<String, Value>>,
) -> PyResult<Chunk> {
    let overrides = overrides(options, None)?;
    let mut axes = Vec::new();
    for text in &params {
        axes.push(parse_parameter_axis(text).map_err(failure)?);
    }
    for text in &initial {
        axes.push(parse_initial_axis(text).map_err(failure)?);
    }
    let random = random.map(|count| Random { count, seed });
    let mut loaded = match model {
        Some((kind, expression, coordinates, forces, symmetries, constraints, parameters)) => {
            let hamiltonian = kind == "hamiltonian";
            Scene::of_text_model(
                (!hamiltonian).then(|| expression.clone()),
                hamiltonian.then_some(expression),
                coordinates,
                forces,
                symmetries,
                constraints,
                parameters,
            )
        }
        None => load(scene)?,
    };
    if let Some(base) = base {
        set_initial(&mut loaded, base)?;
    }
    let ensemble = Ensemble::new(loaded, &overrides, axes, random).map_err(failure)?;
    let count = ensemble.members.len();
    let stop = stop.unwrap_or(count).min(count);
    let start = start.min(stop);
    let outcomes = interruptible(py, |flag| {
        ensemble.run(start..stop, threads, &|| {}, Some(flag))
    })?
    .map_err(failure)?;
    let table = ensemble.table(start, &outcomes);
    let rows = table
        .rows
        .iter()
        .map(|row| {
            row.iter()
                .map(|cell| match cell {
                    Cell::Number(x) => x.into_pyobject(py).map(|x| x.into_any().unbind()),
                    Cell::Integer(n) => n.into_pyobject(py).map(|x| x.into_any().unbind()),
                    Cell::Text(text) => text.into_pyobject(py).map(|x| x.into_any().unbind()),
                    Cell::Empty => Ok(py.None()),
                })
                .collect::<Result<Vec<_>, std::convert::Infallible>>()
        })
        .collect::<Result<Vec<_>, std::convert::Infallible>>()
        .unwrap_or_else(|never| match never {});
    Ok((count, table.columns, rows))
}

/// The states of a solve of a right-hand side: every accepted step's (t, q, p), row by row.
struct Steps(Vec<f64>);

impl<L> svi::observer::Observer<L, svi::PhasePoint<svi::Dyn>> for Steps {
    /// The steps after the initial point.
    fn wants(&self, step: usize) -> bool {
        step > 0
    }

    fn observe(
        &mut self,
        _: &L,
        _: usize,
        point: &svi::PhasePoint<svi::Dyn>,
    ) -> std::ops::ControlFlow<()> {
        self.0.push(point.t);
        self.0.extend(point.q.iter().chain(point.p.iter()));
        std::ops::ControlFlow::Continue(())
    }
}

/// A Python function of (t, y) returning a contiguous array of `size` float64 numbers (the
/// package's wrapper makes it one), as the code a [`HamiltonianRhs`] calls: it writes the result into `out`, or keeps the exception it raised
/// (or a result of another shape) in `raised` and writes NaN, which fails the step.
fn python_function(
    function: Py<PyAny>,
    what: &'static str,
    size: usize,
    raised: &Raised,
) -> impl Fn(f64, &[f64], &mut [f64]) + Send + Sync + 'static {
    let raised = std::sync::Arc::clone(raised);
    move |t: f64, y: &[f64], out: &mut [f64]| {
        let result = Python::attach(|py| -> PyResult<()> {
            let value = function.call1(py, (t, PyArray1::from_slice(py, y)))?;
            let array: PyReadonlyArray1<'_, f64> = value.extract(py).map_err(|_| {
                PyTypeError::new_err(format!(
                    "{what}(t, y) returned something that is not an array of numbers"
                ))
            })?;
            let values = array.as_slice()?;
            if values.len() != size {
                return Err(PyTypeError::new_err(format!(
                    "{what}(t, y) returned {} numbers, not {size}",
                    values.len()
                )));
            }
            out.copy_from_slice(values);
            Ok(())
        });
        if let Err(error) = result {
            raised
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .get_or_insert(error);
            out.fill(f64::NAN);
        }
    }
}

/// The Octave package's call `[T, Y] = spectralvarint(odefun, tspan, y0)` (`svi.solve` with a
/// callable): y' = `odefun`(t, y) with y = (q, p) of 2N entries, from `y0` at `times[0]`, run
/// by `method` (default `svi-h`) through [`svi::solve`] on a [`HamiltonianRhs`] — step
/// doubling to `tol` (default 1e-8) unless `adapt = "none"` with the step `h`. Returns the
/// summary (JSON: `steps` counts every step the method took, trial steps of step doubling
/// included, as `svi run`'s summary; `accepted_steps` those the solution is made of) and the
/// rows (t, q, p): at every accepted step for two `times`, else at the
/// listed times. An exception `odefun` or `jacobian` raises is raised again.
#[pyfunction]
#[pyo3(signature = (odefun, times, y0, *, jacobian=None, method=None, h=None, tol=None, adapt=None, max_steps=None))]
#[allow(clippy::too_many_arguments)]
fn solve_rhs<'py>(
    py: Python<'py>,
    odefun: Py<PyAny>,
    times: Vec<f64>,
    y0: Vec<f64>,
    jacobian: Option<Py<PyAny>>,
    method: Option<String>,
    h: Option<f64>,
    tol: Option<f64>,
    adapt: Option<String>,
    max_steps: Option<usize>,
) -> PyResult<(String, Trajectory<'py>)> {
    let size = y0.len();
    if size == 0 || size % 2 == 1 {
        return Err(invalid(
            "y0",
            format!("y0 = (q, p) has an even number of entries, at least 2, not {size}"),
        ));
    }
    let n = size / 2;
    if times.len() < 2 {
        return Err(invalid(
            "t_span",
            format!("needs at least two times (t0, t_end), not {}", times.len()),
        ));
    }
    let raised = Raised::default();
    let mut model = HamiltonianRhs::new(n, python_function(odefun, "odefun", size, &raised))
        .map_err(|error| failure(error.into()))?;
    if let Some(jacobian) = jacobian {
        model = model.with_jacobian(python_function(jacobian, "jac", size * size, &raised));
    }
    let spec: svi::MethodSpec = method
        .as_deref()
        .unwrap_or("svi-h")
        .parse()
        .map_err(|error: svi::Error| failure(error.into()))?;
    let mut options = svi::SolveOptions::default();
    options.h = h;
    if let Some(max_steps) = max_steps {
        options.max_steps = max_steps;
    }
    if let Some(adapt) = adapt {
        options.adapt = adapt
            .parse()
            .map_err(|error: svi::Error| failure(error.into()))?;
    }
    if tol.is_some() {
        options.tol = tol;
    }
    let every_step = times.len() == 2;
    let span = if every_step {
        svi::Span::new(times[0], times[1])
    } else {
        svi::Span::times(&times)
    };
    let initial = svi::Initial::Momentum {
        q: nalgebra::DVector::from_column_slice(&y0[..n]),
        p: nalgebra::DVector::from_column_slice(&y0[n..]),
    };
    let mut steps = Steps(Vec::new());
    let result = spec.vector_method().and_then(|method| {
        svi::Integrator::new(model, method)
            .try_solve(&span, initial, &options, &mut steps)
            .map_err(|failure| failure.error)
    });
    if let Some(error) = raised.lock().unwrap_or_else(|e| e.into_inner()).take() {
        return Err(error);
    }
    let solution = result.map_err(|error| failure(error.into()))?;
    let mut rows = Vec::new();
    for point in &solution.points {
        if every_step && point.t != times[0] {
            // The accepted steps, which end with the last point.
            rows.extend(&steps.0);
            break;
        }
        rows.push(point.t);
        rows.extend(point.q.iter().chain(point.p.iter()));
    }
    let names: Vec<String> = (1..=n).map(|i| format!("q{i}")).collect();
    let columns = std::iter::once("t".to_string())
        .chain(names.iter().map(|name| format!("q_{name}")))
        .chain(names.iter().map(|name| format!("p_{name}")))
        .collect();
    let summary = serde_json::json!({
        "model": "rhs",
        "method": spec.canonical().to_string(),
        "coordinates": names,
        "status": "ok",
        "t0": times[0],
        "t_end": solution.last.t,
        "steps": solution.statistics.steps,
        "accepted_steps": solution.adaptivity.accepted,
        "rejected_steps": solution.adaptivity.rejected,
        "evaluations": solution.statistics.evaluations,
        "q": solution.last.q.as_slice(),
        "p": solution.last.p.as_slice(),
    });
    Ok((summary.to_string(), (columns, array(py, rows))))
}

/// The zoo models on ℝᴺ (name, coordinates, parameters, default step and horizon, Noether
/// momenta, exact solution), as JSON.
#[pyfunction]
fn models() -> PyResult<String> {
    serde_json::to_string(&svi_experiments::describe_models())
        .map_err(|error| invalid("models", error.to_string()))
}

/// The built-in scenes: (name, the first line of its file).
#[pyfunction]
fn scenes() -> Vec<(&'static str, String)> {
    svi_experiments::BUILTIN_SCENES
        .iter()
        .map(|(name, text)| {
            let line = text.lines().next().unwrap_or("");
            (*name, line.trim_start_matches('#').trim().to_string())
        })
        .collect()
}

/// `svi stability`'s arguments, parsed as the binary parses them.
#[derive(clap::Parser)]
struct StabilityCommand {
    #[command(flatten)]
    args: svi_experiments::stability::StabilityArgs,
}

/// `svi bench`'s arguments, parsed as the binary parses them.
#[derive(clap::Parser)]
struct BenchCommand {
    #[command(flatten)]
    args: svi_experiments::bench::BenchArgs,
}

/// Parse command-line `args` of `command` (a clap error is bad input).
fn parse<T: clap::Parser>(command: &str, args: Vec<String>) -> PyResult<T> {
    T::try_parse_from(std::iter::once(command.to_string()).chain(args)).map_err(|error| {
        let message = error.to_string();
        let first = message
            .lines()
            .next()
            .unwrap_or("")
            .trim_start_matches("error: ");
        failure(SceneError::InvalidOption {
            option: "arguments",
            reason: first.to_string(),
        })
    })
}

/// Linear stability as `svi stability ARGS` computes it (`--method`, `--z` or `--z-min`,
/// `--z-max`, `--samples`): the CSV of the points and, for a range, the regions as JSON.
#[pyfunction]
fn stability(py: Python<'_>, args: Vec<String>) -> PyResult<(String, Option<String>)> {
    use svi_experiments::stability::{Answer, run, to_csv};
    let command: StabilityCommand = parse("stability", args)?;
    let spec: svi::MethodSpec = command
        .args
        .method
        .parse()
        .map_err(|error| invalid("method", format!("{error}")))?;
    let request = command.args.request();
    let answer = py.detach(|| run(spec, &request)).map_err(failure)?;
    Ok(match answer {
        Answer::Points(points) => (to_csv(&points), None),
        Answer::Report(report) => {
            let intervals = |list: &[svi::analysis::stability::Interval]| {
                list.iter()
                    .map(|interval| [interval.lower, interval.upper])
                    .collect::<Vec<_>>()
            };
            let regions = serde_json::json!({
                "stable": intervals(&report.stable),
                "periodic": intervals(&report.periodic),
                "strongly_stable": intervals(&report.strongly_stable),
                "a_stable": report.a_stable,
                "p_stable": report.p_stable,
            });
            (to_csv(&report.points), Some(regions.to_string()))
        }
    })
}

/// A work–precision sweep as `svi bench ARGS` runs it: the records as JSON.
#[pyfunction]
#[pyo3(name = "bench")]
fn work_precision(py: Python<'_>, args: Vec<String>) -> PyResult<String> {
    let command: BenchCommand = parse("bench", args)?;
    let (overrides, options) = command.args.options().map_err(failure)?;
    let name = command
        .args
        .scene
        .as_deref()
        .unwrap_or(svi_experiments::DEFAULT_SCENE);
    let mut scene = load(name)?;
    scene.apply(&overrides).map_err(failure)?;
    let sweeps = py
        .detach(|| svi_experiments::bench::work_precision(&scene, &options))
        .map_err(failure)?;
    let object = serde_json::json!({ "records": sweeps.records, "failures": sweeps.failures });
    Ok(object.to_string())
}

/// The svi version.
#[pyfunction]
fn version() -> &'static str {
    env!("CARGO_PKG_VERSION")
}

/// The native module.
#[pymodule]
fn _svi(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("Failure", m.py().get_type::<Failure>())?;
    m.add_function(wrap_pyfunction!(run, m)?)?;
    m.add_function(wrap_pyfunction!(solve_rhs, m)?)?;
    m.add_function(wrap_pyfunction!(gradient, m)?)?;
    m.add_function(wrap_pyfunction!(options, m)?)?;
    m.add_class::<Dense>()?;
    m.add_function(wrap_pyfunction!(ensemble, m)?)?;
    m.add_function(wrap_pyfunction!(models, m)?)?;
    m.add_function(wrap_pyfunction!(scenes, m)?)?;
    m.add_function(wrap_pyfunction!(version, m)?)?;
    m.add_function(wrap_pyfunction!(stability, m)?)?;
    m.add_function(wrap_pyfunction!(work_precision, m)?)?;
    Ok(())
}
