"""svi — structure-preserving simulation of mechanical systems, from Python.

The numbers come from the Rust core through the experiments library behind the command line, in
memory: ``svi.run("kepler")`` gives exactly the numbers of ``svi run kepler --json``, and
``svi.ensemble(...)`` exactly the table of ``svi ensemble ... --out``. A model of your own is a
:class:`Lagrangian` written as an expression, solved by :func:`solve`:

>>> import svi
>>> pendulum = svi.Lagrangian("0.5*vth^2 + cos(th)", q=["th"])
>>> sol = svi.solve(pendulum, (0.0, 10.0), q0=[1.0], v0=[0.0], method="svi:7/6", h=0.1, dense=True)
>>> sol(2.5)                # q(2.5), read off the step's own polynomial
>>> result = svi.run("kepler", method="svi:7/6", t_end=20.0, params={"e": 0.6})
>>> result.q[-1]            # the final configuration, a NumPy array
>>> result.energy_error_max # any field of the JSON summary, as an attribute
>>> table = svi.ensemble("kepler", params={"e": [0.1, 0.3, 0.5]}, t_end=20.0)

Failures raise :class:`SviError` (a subclass per kind, e.g. :class:`InvalidParameterError`,
:class:`NonConvergenceError`) with the fields of the JSON failure object: ``kind``, ``message``,
``step``, ``t``, and ``summary`` for a run that failed after it started.
"""

from __future__ import annotations

import json
import math
import os
import warnings
from typing import Any, Callable, Dict, Iterator, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from . import _events, _svi
from ._events import Event

__version__: str = _svi.version()

__all__ = [
    "DEFAULT_SCENE",
    "ArgumentTypeError",
    "DivergedError",
    "Event",
    "Gradient",
    "Hamiltonian",
    "HealthError",
    "InvalidInputError",
    "InvalidParameterError",
    "Lagrangian",
    "LegendreMapError",
    "NonConvergenceError",
    "NonFiniteError",
    "OutputError",
    "Array",
    "Result",
    "SingularMatrixError",
    "Solution",
    "StepSizeTooSmallError",
    "TooManyStepsError",
    "SviError",
    "SviWarning",
    "bench",
    "ensemble",
    "gradient",
    "models",
    "options",
    "run",
    "scenes",
    "solve",
    "stability",
]

#: The scene ``svi run`` runs without a name.
DEFAULT_SCENE = "kepler"


class SviError(Exception):
    """A failed svi call, with the fields of ``svi run --json``'s failure object.

    Attributes:
        kind: the error kind: ``invalid_parameter``, ``non_convergence``, ``singular_matrix``,
            ``legendre_map``, ``step_size_too_small``, ``non_finite``, ``diverged``, ``too_many_steps``,
            ``invalid_input``, ``output`` or ``health``.
        message: the message, as ``svi`` prints it.
        step: the index of the failing step (failures in a step), else ``None``.
        t: the time of the failure (the start of the failing step), else ``None``.
        bad_input: whether the input was at fault (``svi`` exits with status 2) rather than a
            run that started (status 1).
        summary: for a run that failed after it started, its summary up to the last good
            state (a dict, as ``svi run --json`` prints it); else ``None``.
    """

    def __init__(
        self,
        kind: str,
        message: str,
        step: Optional[int] = None,
        t: Optional[float] = None,
        bad_input: bool = False,
        summary: Optional[Dict[str, Any]] = None,
    ) -> None:
        super().__init__(message)
        self.kind = kind
        self.message = message
        self.step = step
        self.t = t
        self.bad_input = bad_input
        self.summary = summary

    def __repr__(self) -> str:
        return f"{type(self).__name__}(kind={self.kind!r}, message={self.message!r}, step={self.step!r}, t={self.t!r})"


class SviWarning(UserWarning):
    """A warning of svi: part of a result is missing (a method of :func:`bench` that measured
    no point), or a run's health check failed."""


class InvalidParameterError(SviError, ValueError):
    """A value the library rejects (``invalid_parameter``): a model parameter, a step, a method option."""


class InvalidInputError(SviError, ValueError):
    """Other bad input (``invalid_input``): an unknown scene or model, an option the scene cannot use."""


class ArgumentTypeError(InvalidInputError, TypeError):
    """An argument of the wrong type (``invalid_input``): a bool or a string where a number
    goes, a fractional count, a number where a name goes. Also a :class:`TypeError`."""


class NonConvergenceError(SviError):
    """A nonlinear solve of a step that did not converge (``non_convergence``)."""


class SingularMatrixError(SviError):
    """A singular Newton matrix (``singular_matrix``)."""


class LegendreMapError(SviError):
    """A Legendre map that could not be inverted (``legendre_map``)."""


class StepSizeTooSmallError(SviError):
    """Adaptivity or recovery that needed a step below the smallest allowed (``step_size_too_small``)."""


class TooManyStepsError(SviError):
    """A run that used up its step budget (``max_steps``) before the horizon (``too_many_steps``)."""


class NonFiniteError(SviError):
    """A state or energy that is not a finite number (``non_finite``)."""


class DivergedError(SviError):
    """A state beyond the divergence limit (``diverged``)."""


class OutputError(SviError):
    """An output that could not be written (``output``)."""


class HealthError(SviError):
    """A failed health check (``health``)."""


_ERRORS: Dict[str, type] = {
    "invalid_parameter": InvalidParameterError,
    "invalid_input": InvalidInputError,
    "non_convergence": NonConvergenceError,
    "singular_matrix": SingularMatrixError,
    "legendre_map": LegendreMapError,
    "step_size_too_small": StepSizeTooSmallError,
    "non_finite": NonFiniteError,
    "diverged": DivergedError,
    "too_many_steps": TooManyStepsError,
    "output": OutputError,
    "health": HealthError,
}


def _error(failure: Exception) -> SviError:
    """The :class:`SviError` of a native failure (its argument is the failure object's JSON)."""
    fields = json.loads(failure.args[0])
    cls = _ERRORS.get(fields["kind"], SviError)
    return cls(
        fields["kind"],
        fields["message"],
        fields.get("step"),
        fields.get("t"),
        bool(fields.get("bad_input")),
        fields.get("summary"),
    )


def _wrong_type(name: str, expected: str, value: Any) -> ArgumentTypeError:
    """The error of argument ``name`` given ``value`` where ``expected`` goes."""
    message = f"invalid {name}: {value!r} is a {type(value).__name__}, not {expected}"
    return ArgumentTypeError("invalid_input", message, bad_input=True)


def _is_number(value: Any) -> bool:
    """Whether ``value`` is a real number (not a bool, which Python counts as one)."""
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, (bool, np.bool_))


def _real(name: str, value: Any) -> Optional[float]:
    """``value`` as a float, ``None`` kept; anything but a real number is an :class:`ArgumentTypeError`."""
    if value is None:
        return None
    if not _is_number(value):
        raise _wrong_type(name, "a number", value)
    return float(value)


def _count(name: str, value: Any) -> Optional[int]:
    """``value`` as a whole number of 0 or more, ``None`` kept."""
    if value is None:
        return None
    if not _is_number(value) or not float(value).is_integer():
        raise _wrong_type(name, "a whole number", value)
    count = int(value)
    if not 0 <= count < 2**63:
        raise InvalidParameterError("invalid_parameter", f"invalid {name}: {count}; need a whole number from 0 to 2^63 - 1", bad_input=True)
    return count


def _whole(name: str, value: Any) -> int:
    """``value`` as a whole number of 0 or more, where ``None`` is not one (an argument with
    a numeric default)."""
    if value is None:
        raise _wrong_type(name, "a whole number", value)
    return _count(name, value)


def _text(name: str, value: Any) -> Optional[str]:
    """``value`` as a string (a path-like object as its path), ``None`` kept."""
    if value is None:
        return None
    if isinstance(value, os.PathLike):
        return os.fspath(value)
    if not isinstance(value, str):
        raise _wrong_type(name, "a string", value)
    return value


def _reals(name: str, values: Any) -> Optional[List[float]]:
    """A sequence (or array) of real numbers as a list of floats, ``None`` kept."""
    if values is None:
        return None
    if isinstance(values, (str, bytes)) or _is_number(values):
        raise _wrong_type(name, "a sequence of numbers", values)
    try:
        items = list(np.asarray(values).ravel())
    except (TypeError, ValueError):
        raise _wrong_type(name, "a sequence of numbers", values) from None
    return [_real(name, x) for x in items]


def _names(name: str, values: Any) -> Optional[List[str]]:
    """Names as a list: a sequence of strings, or one string of comma-separated names."""
    if values is None:
        return None
    if isinstance(values, str):
        return [item.strip() for item in values.split(",")]
    try:
        items = list(values)
    except TypeError:
        raise _wrong_type(name, "a list of names", values) from None
    return [_text(name, item) for item in items]


def _listed(name: str, values: Optional[List[Any]]) -> Optional[List[Any]]:
    """``values``, the entries of a flag's comma-separated list, if there is at least one
    (``None`` kept): an empty list is an error naming the keyword, not the flag's parse error
    (``saveat=[]`` said "invalid value '' for '--output-times <LIST>'")."""
    if values is not None and len(values) == 0:
        raise InvalidParameterError("invalid_parameter", f"invalid {name}: the list is empty; give at least one value", bad_input=True)
    return values


def _call(function: Callable[..., Any], *args: Any, **kwargs: Any) -> Any:
    """Call a native function, raising its failures as :class:`SviError`."""
    try:
        return function(*args, **kwargs)
    except _svi.Failure as failure:
        raise _error(failure) from None


class Array(np.ndarray):
    """A NumPy array that prints every digit: each number as its shortest exact decimal (the
    digits of ``svi run --json``), instead of NumPy's 8 significant digits."""

    def __str__(self) -> str:
        if self.dtype.kind != "f":
            return np.ndarray.__str__(np.asarray(self))
        exact = {"float_kind": lambda x: repr(float(x))}
        return np.array2string(np.asarray(self), formatter=exact, separator=", ", max_line_width=120)

    def __repr__(self) -> str:
        return f"Array({self})"


def _exact(values: np.ndarray) -> Array:
    """``values`` as an :class:`Array` (a view, no copy)."""
    return np.asarray(values, dtype=float).view(Array)


class Result:
    """The result of :func:`run`: the summary of ``svi run --json`` and the trajectory.

    Attributes:
        summary: the JSON summary as a dict (every field is also an attribute:
            ``result.energy_error_max``, ``result.steps``, ...).
        t: times of the trajectory's points (every step, or the initial time and the output
            times), a NumPy array (an :class:`Array`, which prints every digit); ``None``
            without a trajectory.
        q, v, p: configuration, velocity and momentum at those times, arrays of shape
            (points, N) (scenes on ℝᴺ; ``None`` for rigid bodies). A chain's trajectory holds
            its observables instead (``trajectory``), and asking for ``q`` says so; its final
            state is ``summary["q"]``.
        energy: energy at those times.
        multipliers: a constrained run's Lagrange multipliers at those times, an array of shape
            (points, m) for m constraints, with ``multipliers=True``; else ``None``.
        trajectory: every column of the trajectory by name (``t``, ``q_q1``, ..., on SO(3)
            ``qw``, ..., ``omega_1``, ..., on the other Lie groups ``g_1``, ..., ``xi_1``, ...,
            ``mu_1``, ..., ``defect``).
    """

    def __init__(self, summary: Dict[str, Any], trajectory: Optional[Tuple[List[str], np.ndarray]]) -> None:
        self.summary: Dict[str, Any] = summary
        self.trajectory: Dict[str, np.ndarray] = {}
        self.t: Optional[np.ndarray] = None
        self.energy: Optional[np.ndarray] = None
        self.multipliers: Optional[np.ndarray] = None
        # A chain's trajectory holds t, energy and its observables, not its n coordinates.
        chain = "coordinates" not in summary and "form" not in summary
        self._chain_columns: Optional[List[str]] = None
        if not chain:
            self.q: Optional[np.ndarray] = None
            self.v: Optional[np.ndarray] = None
            self.p: Optional[np.ndarray] = None
        if trajectory is not None:
            columns, values = trajectory
            # The run's numbers row by row, an array that owns them (no copy).
            data = _exact(values.reshape(-1, len(columns)))
            self.trajectory = {name: data[:, i] for i, name in enumerate(columns)}
            self.t = self.trajectory.get("t")
            self.energy = self.trajectory.get("energy")
            if chain:
                self._chain_columns = columns
            for field in ("q", "v", "p"):
                indices = [i for i, name in enumerate(columns) if name.startswith(field + "_")]
                if indices and not chain:
                    # The columns of q (v, p) are adjacent: a view of the run's buffer.
                    setattr(self, field, data[:, indices[0] : indices[-1] + 1])
            indices = [i for i, name in enumerate(columns) if name.startswith("lambda_")]
            if indices:
                self.multipliers = data[:, indices[0] : indices[-1] + 1]

    def __getattr__(self, name: str) -> Any:
        columns = self.__dict__.get("_chain_columns")
        if name in ("q", "v", "p") and columns is not None:
            raise AttributeError(
                f"a chain's trajectory holds the columns {', '.join(columns)}, not its n coordinates: "
                f"the final {name} is result.summary[{name!r}], and the states at output_times are in "
                "result.summary['outputs']"
            )
        summary = self.__dict__.get("summary", {})
        if name in summary:
            return summary[name]
        raise AttributeError(f"Result has no attribute {name!r} (summary fields: {', '.join(summary)})")

    def __dir__(self) -> List[str]:
        return sorted(set(super().__dir__()) | set(self.summary))

    def __repr__(self) -> str:
        s = self.summary
        return (
            f"Result(model={s.get('model')!r}, method={s.get('method')!r}, steps={s.get('steps')}, "
            f"t_end={s.get('t_end')}, status={s.get('status')!r})"
        )


def run(
    scene: str = DEFAULT_SCENE,
    method: Optional[str] = None,
    *,
    h: Optional[float] = None,
    t_end: Optional[float] = None,
    params: Optional[Mapping[str, float]] = None,
    initial: Optional[Mapping[str, Union[float, Sequence[float]]]] = None,
    diagnostics: Optional[Sequence[str]] = None,
    output_times: Optional[Sequence[float]] = None,
    points: Optional[int] = None,
    quadrature: Optional[int] = None,
    adapt: Optional[str] = None,
    monitor: Optional[str] = None,
    tol: Optional[float] = None,
    recovery: Optional[str] = None,
    divergence_limit: Optional[float] = None,
    max_steps: Optional[int] = None,
    form: Optional[str] = None,
    trajectory: bool = True,
    every: Optional[int] = None,
    progress: Optional[bool] = None,
    **options: Any,
) -> Result:
    """Run a scene, as ``svi run SCENE --json`` does, and return its summary and trajectory.

    Args:
        scene: a built-in scene (:func:`scenes`), a zoo model's name (:func:`models`; run with
            its defaults), a path to a scene TOML file, or the text of a scene (TOML).
        method: ``NAME``, ``NAME:P`` or ``NAME:P/M``, e.g. ``"svi:7/6"``, ``"sc:9"``, ``"verlet"``.
        h: the step.  t_end: the final time.
        params: model parameters, ``{"e": 0.9}``.
        initial: initial-state fields, ``{"q": [...], "v": [...]}`` (or ``p``; ``t0``; on SO(3)
            ``rotation``/``quaternion`` and ``omega``/``momentum``; on the other Lie groups
            ``g``/``log`` and ``xi``/``momentum``).
        diagnostics: any of ``"energy"``, ``"momentum"``, ``"solution"``, or ``["none"]``.
        output_times: report (and record in the trajectory) the states at these times.
        points, quadrature, adapt, monitor, tol, recovery, divergence_limit, max_steps, form: as the flags
            of ``svi run`` of the same names (``adapt="reparam", monitor="sundman:1"``: fixed
            steps ``h`` in computational time τ, dt = |q| dτ).
        trajectory: record every step (or the output times) as arrays ``t``, ``q``, ``v``, ``p``.
        every: record every ``every``-th step only (the last step is always recorded).
        progress: show ``svi run``'s progress bar on stderr for runs of 10⁴ steps and more
            (default: when stderr is a terminal; in a notebook, ensembles show a tqdm bar).

    Raises:
        SviError: the subclass of the failure's kind, with its fields.
    """
    initial_lists = None
    if initial is not None:
        initial_lists = {
            _text("initial", name): _reals(f"initial[{name!r}]", [value] if _is_number(value) else value)
            for name, value in _mapping("initial", initial).items()
        }
    checked = _shared_options(locals(), options, "run")
    callables = _events.split(checked)
    summary, rows, _ = _call(
        _svi.run,
        _text("scene", scene),
        params=_parameters(params),
        initial=initial_lists,
        options=checked,
        events=callables,
        trajectory=_flag("trajectory", trajectory),
        every=_count("every", every),
        progress=_stderr_is_terminal() if progress is None else _flag("progress", progress),
    )
    return Result(json.loads(summary), rows)


class Gradient:
    """The gradient of a loss over a run (:func:`gradient`).

    Attributes:
        value: J, the loss summed over the outputs.
        gradient: ∂J/∂(column), a NumPy array in the order of ``columns``.
        columns: what each entry differentiates with respect to, in the order of ``wrt``: the
            blocks ``q0`` and ``v0`` (``p0`` for a start in momenta) as ``q0_NAME`` and
            ``v0_NAME`` per coordinate, then the parameters by name; ``result["e"]`` picks
            one entry.
        peak_stored: the most forward states (checkpoints) and tangent maps held at once.
        peak_bytes: the memory they took, in bytes.
    """

    def __init__(self, fields: Dict[str, Any]) -> None:
        self.value: float = fields["value"]
        self.columns: List[str] = fields["columns"]
        self.gradient: np.ndarray = _exact(np.array(fields["gradient"], dtype=float))
        self.peak_stored: int = fields["peak_stored"]
        self.peak_bytes: int = fields["peak_bytes"]

    def __getitem__(self, column: str) -> float:
        """∂J/∂``column``."""
        return float(self.gradient[self.columns.index(column)])

    def __repr__(self) -> str:
        entries = ", ".join(f"{name}={float(x)!r}" for name, x in zip(self.columns, self.gradient))
        return f"Gradient(value={self.value!r}, {entries})"


def gradient(
    scene: str,
    loss: Callable[[int, float, np.ndarray, np.ndarray], Tuple[Any, Any, Any]],
    wrt: Union[str, Sequence[str]],
    method: Optional[str] = None,
    *,
    h: Optional[float] = None,
    t_end: Optional[float] = None,
    every: Optional[int] = None,
    checkpoints: Optional[int] = None,
    params: Optional[Mapping[str, float]] = None,
    initial: Optional[Mapping[str, Union[float, Sequence[float]]]] = None,
) -> Gradient:
    """The gradient of a loss of a run, J = Σ_j ℓ_j(t_j, q(t_j), q̇(t_j)), with respect to the
    initial state and the model's parameters, by the discrete adjoint: the exact gradient of
    the method's discrete map (as ``svi run --sensitivity``, whose Jacobians give the same
    numbers one output at a time), the forward states kept at ``checkpoints``.

    Args:
        scene: a scene or zoo model whose parameters can be differentiated (``"kepler"``,
            ``"damped-pendulum"``), run with fixed steps.
        loss: ``loss(j, t, q, v)`` at output ``j`` (0: the start; then every ``every``-th step
            and the last step) returns ``(ℓ_j, ∂ℓ_j/∂q, ∂ℓ_j/∂q̇)``: a number and two arrays of
            the model's dimension. A least-squares loss ½Σ|q(t_j) − d_j|² returns
            ``(0.5 * r @ r, r, 0 * v)`` with ``r = q - d[j]``.
        wrt: what to differentiate with respect to: parameter names and the initial-state
            blocks ``"q0"`` and ``"v0"`` (or ``"p0"``), as a list or ``"e,q0"``.
        method, h, t_end, params, initial: as :func:`run`.
        every: an output every ``every`` steps (default: the start and the last step only).
        checkpoints: how many forward states are kept (at least 1; default ⌈√K⌉ for K steps).

    Raises:
        SviError: an unknown name in ``wrt``, a scene that cannot be differentiated, a loss
            whose value or gradient is not finite (:class:`NonFiniteError`, naming the output),
            ``checkpoints=0``; ``loss``'s own exceptions are raised as they are.
    """

    def native(j: int, t: float, q: np.ndarray, v: np.ndarray) -> Tuple[float, List[float], List[float]]:
        returned = loss(j, t, q, v)
        try:
            value, dq, dv = returned
            dq = np.asarray(dq, dtype=float).ravel()
            dv = np.asarray(dv, dtype=float).ravel()
        except (TypeError, ValueError):
            raise _wrong_type("loss", "a tuple (value, dl_dq, dl_dv) of a number and two arrays", returned) from None
        if dq.size != len(q) or dv.size != len(v):
            message = f"invalid loss: its gradient at output {j} has {dq.size} and {dv.size} entries, not {len(q)} each"
            raise ArgumentTypeError("invalid_input", message, bad_input=True)
        return _real("loss", value), dq.tolist(), dv.tolist()

    initial_lists = None
    if initial is not None:
        initial_lists = {
            _text("initial", name): _reals(f"initial[{name!r}]", [value] if _is_number(value) else value)
            for name, value in _mapping("initial", initial).items()
        }
    if not callable(loss):
        raise _wrong_type("loss", "a function", loss)
    names = _names("wrt", wrt)
    if not names or not all(names):
        message = f"invalid wrt: {wrt!r} names nothing to differentiate with respect to"
        raise InvalidInputError("invalid_input", message, bad_input=True)
    named = {"method": method, "h": h, "t_end": t_end, "sensitivity": names, "sensitivity_every": every}
    checked = _shared_options(named, {}, "gradient")
    fields = _call(
        _svi.gradient,
        _text("scene", scene),
        native,
        params=_parameters(params),
        initial=initial_lists,
        options=checked,
        checkpoints=_count("checkpoints", checkpoints),
    )
    return Gradient(json.loads(fields))


#: The checks of the kinds of option values (``_svi.options()`` names each option's kind).
_CHECKS: Dict[str, Callable[[str, Any], Any]] = {
    "real": _real,
    "count": _count,
    "text": _text,
    "reals": lambda name, value: _listed(name, _reals(name, value)),
    "names": lambda name, value: _listed(name, _names(name, value)),
    "texts": _events.events,
    "flag": lambda name, value: None if value is None else _flag(name, value),
}

#: The options of ``svi run`` that :func:`run`, :func:`ensemble` and :func:`solve` take as
#: keywords (the flags' names with ``_``: ``t_end`` for ``--t-end``), each with the check of
#: its kind. They come from the native module, whose one definition of them is the command
#: line's: a flag added to ``svi run`` is a keyword of every call.
_SHARED_OPTIONS: Dict[str, Callable[[str, Any], Any]] = {name: _CHECKS[kind] for name, kind in _svi.options()}


def options() -> List[str]:
    """The options of ``svi run`` that :func:`run`, :func:`solve` and :func:`ensemble` take as
    keyword arguments (the flags' names with ``_`` for ``-``)."""
    return list(_SHARED_OPTIONS)


def _shared_options(arguments: Mapping[str, Any], extra: Mapping[str, Any], call: str) -> Dict[str, Any]:
    """The options among a call's named ``arguments`` (its ``locals()``) and its other keyword
    arguments ``extra``, their types checked, those not given left out; a keyword that is no
    option is a ``TypeError``, as Python's for an unexpected keyword."""
    unknown = set(extra) - set(_SHARED_OPTIONS)
    if unknown:
        raise TypeError(f"{call}() got unexpected keyword arguments: {', '.join(sorted(unknown))}")
    given = {name: arguments[name] for name in _SHARED_OPTIONS if name in arguments}
    given.update(extra)
    checked = {name: _SHARED_OPTIONS[name](name, value) for name, value in given.items()}
    return {name: value for name, value in checked.items() if value is not None}


def _mapping(name: str, values: Any) -> Mapping[str, Any]:
    """``values`` if it is a mapping (a dict), else an :class:`ArgumentTypeError`."""
    if not isinstance(values, Mapping):
        raise _wrong_type(name, "a dict", values)
    return values


def _sequence(name: str, values: Any) -> List[Any]:
    """``values`` as a list, if it is a sequence (not a string)."""
    if isinstance(values, (str, bytes)):
        raise _wrong_type(name, "a sequence", values)
    try:
        return list(values)
    except TypeError:
        raise _wrong_type(name, "a sequence", values) from None


def _parameters(params: Any) -> Optional[Dict[str, float]]:
    """Model parameters, name → number, ``None`` kept."""
    if params is None:
        return None
    return {_text("params", name): _real(f"params[{name!r}]", value) for name, value in _mapping("params", params).items()}


def _flag(name: str, value: Any) -> bool:
    """``value`` if it is a bool."""
    if not isinstance(value, (bool, np.bool_)):
        raise _wrong_type(name, "True or False", value)
    return bool(value)


def _stderr_is_terminal() -> bool:
    """Whether stderr is a terminal (where a progress bar can be drawn)."""
    import sys

    try:
        return sys.stderr.isatty()
    except (AttributeError, ValueError):
        return False


def models() -> List[Dict[str, Any]]:
    """The zoo models on ℝᴺ: name, coordinates, parameters (with defaults), default step and
    horizon, Noether momenta, whether an exact solution is known (as ``svi list``)."""
    return json.loads(_svi.models())


def scenes() -> Dict[str, str]:
    """The built-in scenes: name → the first line of its file."""
    return dict(_svi.scenes())


ValuesSpec = Union[str, float, Sequence[float], np.ndarray, Tuple[float, float], Tuple[float, float, int]]


def _number(x: Any) -> str:
    """A number as text that Rust reads back exactly (Python's repr is the shortest round trip)."""
    return repr(float(x))


def _spec(name: str, values: ValuesSpec) -> str:
    """The command-line form ``NAME=SPEC`` of an axis given in Python.

    - a string: the command line's own SPEC (``"0.1:0.9:81"``, ``"0.1,0.3"``);
    - a tuple ``(lo, hi, count)`` with an integer count: a grid, both ends included;
    - a tuple ``(lo, hi)``: a range to draw from (``random=N``);
    - a number, a list or an array: these values.
    """
    name = _text("axis name", name)
    if isinstance(values, str):
        return f"{name}={values}"
    if isinstance(values, tuple) and len(values) == 3:
        lo, hi = _real(f"{name} (lo)", values[0]), _real(f"{name} (hi)", values[1])
        if not _is_number(values[2]) or isinstance(values[2], (float, np.floating)):
            raise _wrong_type(f"{name} (count)", "an int (a tuple (lo, hi, count) is a grid)", values[2])
        return f"{name}={_number(lo)}:{_number(hi)}:{_count(f'{name} (count)', values[2])}"
    if isinstance(values, tuple) and len(values) == 2:
        return f"{name}={_number(_real(f'{name} (lo)', values[0]))}:{_number(_real(f'{name} (hi)', values[1]))}"
    points = _reals(name, [values] if _is_number(values) else values)
    return f"{name}={','.join(_number(x) for x in points)}"


def _column(values: List[Any]) -> Any:
    """A table column as a NumPy array: integers, floats (``nan`` where empty) or objects."""
    present = [v for v in values if v is not None]
    if all(isinstance(v, int) and not isinstance(v, bool) for v in present):
        if len(present) == len(values):
            return np.array(values, dtype=np.int64)
        return np.array([math.nan if v is None else float(v) for v in values], dtype=float)
    if all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in present):
        return np.array([math.nan if v is None else float(v) for v in values], dtype=float)
    return np.array(["" if v is None else v for v in values], dtype=object)


def _chunks(count: int, size: int) -> Iterator[Tuple[int, int]]:
    """The ranges ``[start, stop)`` of ``count`` members in chunks of ``size``."""
    for start in range(0, count, size):
        yield start, min(start + size, count)


def _progress(total: int, show: Optional[bool]) -> Any:
    """A tqdm progress bar over members (notebook or terminal), or ``None`` without tqdm."""
    if show is False:
        return None
    try:
        from tqdm.auto import tqdm
    except ImportError:
        return None
    return tqdm(total=total, unit="member", desc="svi ensemble")


def _run_chunk(arguments: Dict[str, Any], start: int, stop: int) -> Tuple[List[str], List[List[Any]]]:
    """Run members ``start..stop`` of an ensemble (a Dask task: runs in a worker)."""
    _, columns, rows = _call(_svi.ensemble, start=start, stop=stop, **arguments)
    return columns, rows


def ensemble(
    scene: Any = DEFAULT_SCENE,
    params: Optional[Mapping[str, ValuesSpec]] = None,
    initial: Optional[Mapping[str, ValuesSpec]] = None,
    *,
    random: Optional[int] = None,
    seed: int = 0,
    threads: int = 0,
    client: Any = None,
    chunk_size: Optional[int] = None,
    progress: Optional[bool] = None,
    as_frame: Optional[bool] = None,
    method: Optional[str] = None,
    h: Optional[float] = None,
    t_end: Optional[float] = None,
    diagnostics: Optional[Sequence[str]] = None,
    points: Optional[int] = None,
    quadrature: Optional[int] = None,
    adapt: Optional[str] = None,
    monitor: Optional[str] = None,
    tol: Optional[float] = None,
    recovery: Optional[str] = None,
    divergence_limit: Optional[float] = None,
    max_steps: Optional[int] = None,
    form: Optional[str] = None,
    q0: Any = None,
    v0: Any = None,
    p0: Any = None,
    **options: Any,
) -> Any:
    """Run a scene over grids or random draws of parameters and initial states, as ``svi ensemble``.

    Args:
        scene: a built-in scene, a zoo model's name, a scene file or a scene's TOML text, or a
            :class:`Lagrangian` (then ``q0`` and ``v0`` or ``p0``, the state every member starts
            from before its varied components, are needed).
        params: varied model parameters, name → values: a list or array (these values), a
            tuple ``(lo, hi, count)`` (a grid, both ends included, as ``numpy.linspace``), a
            tuple ``(lo, hi)`` (a range, with ``random``), or the command line's SPEC string.
            Several names make the grid of every combination, the first slowest.
        initial: varied initial components, ``"q.alpha1"`` (field ``q``, ``v`` or ``p`` and the
            model's coordinate name or index) → values, as for ``params``.
        random: draw this many members uniformly from the ranges instead of a grid.
        seed: the seed of the draws.
        threads: threads per process (0: every core).
        client: a ``dask.distributed.Client``: the members are run on its workers in chunks
            (each worker runs the Rust core; ``svi`` must be installed there) and gathered in
            member order — the same table as a local run.
        chunk_size: members per chunk (default: about 4 chunks per worker with a client, 1 %
            of the members locally when a progress bar is shown, else all at once).
        progress: show a tqdm progress bar (default: when tqdm is installed).
        as_frame: return a pandas DataFrame (default: when pandas is installed), else a dict
            of column name → NumPy array.
        method, h, t_end, diagnostics, points, quadrature, adapt, monitor, tol, recovery,
        divergence_limit, max_steps, form: shared by every member, as the flags of ``svi ensemble``.

    Returns:
        The member table: one row per member — ``member``, the varied values, ``status``
        (``"ok"`` or the error kind), the final state, the diagnostics, ``steps``, the error.
        A failed member is a row with its error; it never stops the others.

    Raises:
        SviError: bad input of the ensemble itself (unknown scene, parameter or coordinate,
        malformed values).
    """
    base = {
        name: _reals(f"{name}0", np.atleast_1d(value)) for name, value in (("q", q0), ("v", v0), ("p", p0)) if value is not None
    }
    model = scene._native() if isinstance(scene, _TextModel) else None
    checked = _shared_options(locals(), options, "ensemble")
    if _events.split(checked):
        raise TypeError(
            "ensemble(): events are text here (the members run in parallel in Rust); "
            "callables are events of svi.run and svi.solve"
        )
    arguments: Dict[str, Any] = dict(
        scene="" if model is not None else _text("scene", scene),
        model=model,
        base=base or None,
        params=[_spec(name, values) for name, values in _mapping("params", {} if params is None else params).items()],
        initial=[_spec(name, values) for name, values in _mapping("initial", {} if initial is None else initial).items()],
        random=_count("random", random),
        seed=_whole("seed", seed),
        threads=_whole("threads", threads),
        options=checked,
    )
    count, columns, _ = _call(_svi.ensemble, start=0, stop=0, **arguments)
    rows: List[List[Any]] = []
    bar = _progress(count, progress)
    try:
        if client is not None:
            workers = max(1, len(client.scheduler_info().get("workers", {})))
            size = chunk_size or max(1, math.ceil(count / (4 * workers)))
            ranges = list(_chunks(count, size))
            futures = [client.submit(_run_chunk, arguments, start, stop, pure=False) for start, stop in ranges]
            if bar is not None:
                from dask.distributed import as_completed

                for future in as_completed(futures):
                    start, stop = ranges[futures.index(future)]
                    bar.update(stop - start)
            for chunk_columns, chunk_rows in client.gather(futures):
                if chunk_columns != columns:
                    raise RuntimeError("a worker's table has other columns: is the same svi installed on every worker?")
                rows.extend(chunk_rows)
        else:
            size = chunk_size or (max(1, math.ceil(count / 100)) if bar is not None else max(1, count))
            for start, stop in _chunks(count, size):
                rows.extend(_run_chunk(arguments, start, stop)[1])
                if bar is not None:
                    bar.update(stop - start)
    finally:
        if bar is not None:
            bar.close()
    table = {name: _column([row[i] for row in rows]) for i, name in enumerate(columns)}
    return _frame(table, columns, as_frame)


def _frame(table: Dict[str, Any], columns: List[str], as_frame: Optional[bool]) -> Any:
    """A table as a pandas DataFrame (when pandas is installed and ``as_frame`` is not False)."""
    if as_frame is not False:
        try:
            import pandas
        except ImportError:
            if as_frame:
                raise
        else:
            return pandas.DataFrame(table, columns=columns)
    return table


def stability(
    method: str = "svi:5/4",
    z: Optional[Sequence[float]] = None,
    *,
    z_min: Optional[float] = None,
    z_max: Optional[float] = None,
    samples: Optional[int] = None,
    as_frame: Optional[bool] = None,
) -> Dict[str, Any]:
    """Linear stability on the harmonic oscillator, as ``svi stability``.

    With ``z`` the stability matrix S(z) at those z = σ²h²; else on [z_min, z_max] (defaults
    1e-6 and 900) at ``samples`` points, with the regions.

    Returns:
        ``{"points": table of z, rho, det, trace, discriminant, strong_margin}``, plus for a
        range ``stable``, ``periodic``, ``strongly_stable`` (lists of [lower, upper]),
        ``a_stable`` and ``p_stable``.
    """
    args = ["--method", _text("method", method)]
    if z is not None:
        args += ["--z", ",".join(_number(x) for x in _listed("z", _reals("z", z)))]
    for flag, value in (("--z-min", _real("z_min", z_min)), ("--z-max", _real("z_max", z_max))):
        if value is not None:
            args += [flag, _number(value)]
    if samples is not None:
        args += ["--samples", str(_count("samples", samples))]
    csv, regions = _call(_svi.stability, args)
    lines = csv.strip().splitlines()
    columns = lines[0].split(",")
    values = np.array([[float(x) for x in line.split(",")] for line in lines[1:]], dtype=float).reshape(-1, len(columns))
    result: Dict[str, Any] = {"points": _frame({name: values[:, i] for i, name in enumerate(columns)}, columns, as_frame)}
    if regions is not None:
        result.update(json.loads(regions))
    return result


def bench(
    scene: str = DEFAULT_SCENE,
    methods: Optional[Union[str, Sequence[str]]] = None,
    *,
    steps: Optional[Sequence[int]] = None,
    tolerances: Optional[Sequence[float]] = None,
    t_end: Optional[float] = None,
    params: Optional[Mapping[str, float]] = None,
    batches: Optional[int] = None,
    min_batch: Optional[float] = None,
    target: Optional[float] = None,
    max_run: Optional[float] = None,
    as_frame: Optional[bool] = None,
) -> Any:
    """A work–precision sweep, as ``svi bench``: one row per (method, step count or tolerance)
    with the final error, energy and momentum errors, evaluations, iterations and median wall
    time. The error is measured against the model's exact solution or, for a model without one
    (a chain, a text model), against a resolved reference run of SVI of order 12, as
    ``svi bench`` measures it. A method none of whose points could be
    measured is left out of the table with an :class:`SviWarning` naming its error; the call
    raises :class:`SviError` only when no method measured any point."""
    args = [_text("scene", scene)]
    if methods is not None:
        args += ["--methods", ",".join(_names("methods", methods))]
    if steps is not None:
        args += ["--steps", ",".join(str(_count("steps", n)) for n in _listed("steps", _sequence("steps", steps)))]
    if tolerances is not None:
        args += ["--tolerances", ",".join(_number(x) for x in _listed("tolerances", _reals("tolerances", tolerances)))]
    if t_end is not None:
        args += ["--t-end", _number(_real("t_end", t_end))]
    for name, value in (_parameters(params) or {}).items():
        args += ["--param", f"{name}={_number(value)}"]
    if batches is not None:
        args += ["--batches", str(_count("batches", batches))]
    for flag, name, value in (("--min-batch", "min_batch", min_batch), ("--target", "target", target), ("--max-run", "max_run", max_run)):
        if value is not None:
            args += [flag, _number(_real(name, value))]
    outcome = json.loads(_call(_svi.bench, args))
    for failure in outcome["failures"]:
        warnings.warn(
            f"{failure['method']} measured no point ({failure['kind']}): {failure['message']}",
            SviWarning,
            stacklevel=2,
        )
    records = outcome["records"]
    columns = list(records[0]) if records else []
    table = {name: _column([record[name] for record in records]) for name in columns}
    return _frame(table, columns, as_frame)


# Models and solutions (after the helpers above, which they use).
from ._solve import Hamiltonian, Lagrangian, Solution, _TextModel, solve  # noqa: E402
