"""Models and solutions: :class:`Lagrangian` written as text (or SymPy), :func:`solve` and the
:class:`Solution` it returns, evaluated at any time by the method's own step polynomials."""

from __future__ import annotations

import json
import re
from typing import Any, Callable, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from . import _events, _svi

# The helpers of the package (argument checks, errors, the result object): this module is
# imported at the end of ``svi/__init__.py``, once they exist.
from . import (  # noqa: E402
    Result,
    _call,
    _count,
    _exact,
    _listed,
    _mapping,
    _real,
    _reals,
    _sequence,
    _shared_options,
    _text,
    _wrong_type,
)


def _expression(name: str, value: Any) -> str:
    """An expression as svi's text grammar reads it: a string as it is, a SymPy expression
    printed (``**`` as ``^``, Euler's number ``E`` as ``e``)."""
    if isinstance(value, str):
        return value
    if type(value).__module__.startswith("sympy"):
        text = str(value).replace("**", "^")
        return re.sub(r"\bE\b", "e", text)
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return repr(float(value))
    raise _wrong_type(name, "a string or a SymPy expression", value)


def _symbol(name: str, value: Any) -> str:
    """A coordinate's name: a string, or a SymPy symbol's name."""
    if isinstance(value, str):
        return value
    if type(value).__module__.startswith("sympy") and hasattr(value, "name"):
        return value.name
    raise _wrong_type(name, "a name (a string or a SymPy symbol)", value)


class _TextModel:
    """A model written as text (:class:`Lagrangian`, :class:`Hamiltonian`): the expression, its
    coordinates, parameters, forces, symmetries and constraints, as the Rust core reads them."""

    def __init__(
        self,
        expr: Any,
        q: Sequence[Any],
        params: Optional[Mapping[str, float]] = None,
        forces: Optional[Sequence[Any]] = None,
        symmetries: Optional[Sequence[Sequence[Any]]] = None,
        constraints: Optional[Sequence[Any]] = None,
    ) -> None:
        self.expr: str = _expression("expr", expr)
        self.q: List[str] = [_symbol("q", name) for name in _sequence("q", q)]
        self.params: Dict[str, float] = {
            _text("params", name): _real(f"params[{name!r}]", value)
            for name, value in _mapping("params", params or {}).items()
        }
        self.forces: Optional[List[str]] = (
            None if forces is None else [_expression("forces", f) for f in _sequence("forces", forces)]
        )
        self.symmetries: Optional[List[List[str]]] = (
            None
            if symmetries is None
            else [[_expression("symmetries", x) for x in _sequence("symmetries", xi)] for xi in _sequence("symmetries", symmetries)]
        )
        self.constraints: Optional[List[str]] = (
            None if constraints is None else [_expression("constraints", g) for g in _sequence("constraints", constraints)]
        )

    #: What the expression is, for the Rust core.
    _kind = "lagrangian"

    def _native(
        self,
    ) -> Tuple[str, str, List[str], Optional[List[str]], Optional[List[List[str]]], Optional[List[str]], Dict[str, float]]:
        return (self._kind, self.expr, self.q, self.forces, self.symmetries, self.constraints, self.params)

    def __repr__(self) -> str:
        constraints = "" if self.constraints is None else f", constraints={self.constraints!r}"
        return f"{type(self).__name__}({self.expr!r}, q={self.q!r}, params={self.params!r}{constraints})"


class Lagrangian(_TextModel):
    """A Lagrangian L(t, q, q̇) written as an expression, for :func:`solve` and :func:`ensemble`.

    The expression names the coordinates ``q``, their velocities (``v`` + the coordinate's
    name: ``vx`` for ``x``), the time ``t`` and the parameters ``params``; it takes
    ``+ - * / ^``, parentheses, ``pi``, ``e`` and ``sin cos tan asin acos atan atan2 sinh cosh
    tanh exp ln log sqrt abs`` (the grammar of scene files' ``lagrangian``). A SymPy expression
    in symbols of those names works as well. Any number of coordinates; a chain of n sites is
    ``q=["q[1..n]"]`` with ``sum(i, 1, n, ...)`` in the expression and ``n`` a parameter.
    Every derivative the methods need comes from it by automatic differentiation in the Rust
    core.

    Args:
        expr: L, a string or a SymPy expression.
        q: the coordinates' names (strings or SymPy symbols).
        params: every parameter the expressions use, with its value.
        forces: optional non-conservative forces f_L(t, q, q̇), one expression per coordinate
            (Lagrange–d'Alembert).
        symmetries: optional generators ξ(q) of symmetries, each one expression per
            coordinate; their Noether momenta are diagnosed (``momentum_error_max``).
        constraints: optional holonomic constraints g(q) = 0, each an expression in the
            coordinates and the parameters (``"x^2 + y^2 - l^2"``): the model then runs with a
            constrained method (``method="rattle"``, the default, or ``"rattle-kahan-li8"``,
            ...), and the solution reports ``constraint_error_max`` and
            ``velocity_constraint_error_max`` (and with ``multipliers=True`` the multipliers).

    >>> pendulum = Lagrangian("0.5*l^2*vth^2 + g*l*cos(th)", q=["th"], params={"g": 9.81, "l": 1.0})
    """

class Hamiltonian(_TextModel):
    """A Hamiltonian H(t, q, p) written as an expression, for :func:`solve` and :func:`ensemble`.

    The expression names the coordinates ``q``, their momenta (``p`` + the coordinate's name:
    ``px`` for ``x``), the time ``t`` and the parameters ``params``, in the grammar of
    :class:`Lagrangian` (a scene file's ``hamiltonian``). ``forces`` are f_H(t, q, p), entering
    as ṗ = −∂H/∂q + f_H; ``symmetries`` as for a Lagrangian. The initial state is ``q0`` and
    ``p0``. Every method runs it: those on Hamilton's equations (``svi-h``, ``sc-h``,
    ``midpoint-h``, ``verlet-h``, ...) from H's derivatives by automatic differentiation, the
    others through the Legendre map q̇ = ∂H/∂p. An H recognised as ½pᵀAp + V(t, q) with a
    constant A runs as fast as the Lagrangian ½q̇ᵀA⁻¹q̇ − V.

    >>> kepler = Hamiltonian("0.5*(px^2 + py^2) - 1/sqrt(x^2 + y^2)", q=["x", "y"])
    >>> sol = solve(kepler, (0.0, 10.0), q0=[1.0, 0.0], p0=[0.0, 1.0], method="svi-h", h=0.1)
    """

    _kind = "hamiltonian"

    def __init__(
        self,
        expr: Any,
        q: Sequence[Any],
        params: Optional[Mapping[str, float]] = None,
        forces: Optional[Sequence[Any]] = None,
        symmetries: Optional[Sequence[Sequence[Any]]] = None,
    ) -> None:
        super().__init__(expr, q, params=params, forces=forces, symmetries=symmetries)


class Solution(Result):
    """The result of :func:`solve`: the summary and trajectory of :class:`Result` (``t``, ``q``,
    ``v``, ``p``, ``energy`` at every step or at ``saveat``; every summary field as an
    attribute, e.g. ``energy_error_max``), and the solution at any time of the span:

    ``sol(t)`` is q(t) read off the polynomial of the step that contains t — the method's own
    dense output (SVI and SC: the step's interpolating polynomial; other methods: the cubic
    Hermite polynomial of the step's ends) — for a number t an array of shape (N,), for an
    array of times one of shape (len(t), N). ``sol(t, "v")`` gives q̇(t), ``sol(t, "p")`` the
    momentum (interpolated between the Legendre map's values at the step's sample points:
    exact for a constant mass).
    """

    def __init__(self, summary: Dict[str, Any], trajectory: Any, dense: Any) -> None:
        super().__init__(summary, trajectory)
        self._dense = dense

    def __call__(self, t: Any, what: str = "q") -> np.ndarray:
        if self._dense is None:
            raise AttributeError(
                "this solution kept no step polynomials: solve(..., dense=True) keeps them "
                "(or ask for saveat=[...] times before the run)"
            )
        if what not in ("q", "v", "p"):
            raise ValueError(f"what is 'q', 'v' or 'p', not {what!r}")
        times = np.asarray(t, dtype=float)
        q, v, p = _call(self._dense.evaluate, np.ascontiguousarray(times.ravel()))
        values = {"q": q, "v": v, "p": p}[what]
        n = self._dense.dimension()
        return _exact(values.reshape(n) if times.ndim == 0 else values.reshape(times.shape + (n,)))

    @property
    def y(self) -> Optional[np.ndarray]:
        """The states (q, p) side by side, an array of shape (points, 2N): the Octave package's
        ``Y`` (``T`` is ``t``)."""
        q, p = self.__dict__.get("q"), self.__dict__.get("p")
        return None if q is None or p is None else _exact(np.hstack([q, p]))

    @property
    def span(self) -> Optional[Tuple[float, float]]:
        """The times the step polynomials cover: (t0, t_end)."""
        return None if self._dense is None else self._dense.span()


def solve(
    model: Union[Lagrangian, Hamiltonian, str, Callable[[float, np.ndarray], Any]],
    t_span: Union[float, Tuple[float, float], Sequence[float]],
    y0: Any = None,
    *,
    jac: Optional[Callable[[float, np.ndarray], Any]] = None,
    q0: Any = None,
    v0: Any = None,
    p0: Any = None,
    method: Optional[str] = None,
    h: Optional[float] = None,
    saveat: Any = None,
    adapt: Optional[str] = None,
    tol: Optional[float] = None,
    diagnostics: Optional[Sequence[str]] = None,
    params: Optional[Mapping[str, float]] = None,
    dense: bool = False,
    **options: Any,
) -> Solution:
    """Solve a model from an initial state over a span of time.

    Args:
        model: a :class:`Lagrangian` or :class:`Hamiltonian`, a zoo model's or built-in
            scene's name (:func:`models`, :func:`scenes`), whose defaults fill what is not
            given — or ``odefun``, a function y' = odefun(t, y) of Hamilton's equations with
            y = (q, p) (below).
        t_span: ``(t0, t_end)``, ``t_end`` (from the model's t0, else 0), or a list of times
            ``[t0, t1, ..., t_end]``: the states at those times (as ``saveat``).
        y0: the initial state (q0, p0) in one array of 2N numbers (the Octave package's
            ``y0``), instead of ``q0`` and ``p0``.
        q0, v0 | p0: the initial configuration and velocity (or momentum); a
            :class:`Lagrangian` needs both, a zoo model has defaults.
        method: ``NAME``, ``NAME:P`` or ``NAME:P/M`` (``"svi:7/6"``, ``"sc:9"``, ``"verlet"``;
            default SVI with 6 points); for a model with constraints a constrained method
            (``"rattle"``, the default, ``"rattle-yoshida4"``, ``"rattle-kahan-li6"``,
            ``"rattle-kahan-li8"``).
        h: the step (the first trial step of ``adapt="step"``; the τ-step of ``"reparam"``).
        saveat: times at which ``t, q, v, p`` are reported, read off the step polynomials
            (default: every step).
        adapt: ``None`` (fixed steps), ``"step"``, ``"degree"``, ``"reparam"`` or ``"sem"``,
            as ``svi run --adapt``; ``tol`` the target of ``"step"`` and ``"degree"``.
        diagnostics: any of ``"energy"``, ``"momentum"``, ``"solution"`` (default energy and
            momentum), or ``["none"]``.
        params: parameter values replacing the model's.
        dense: keep every step's polynomial so that ``sol(t)`` works at any time. It costs K
            evaluations of the step polynomial and the Legendre map per step and their memory
            (K the method's points, at least 4): SVI 7/6 on Kepler runs about 5 times longer.
            Off by default; ``saveat`` gives states at times known before the run for free.
        options: the other options of :func:`run` (``points``, ``quadrature``, ``monitor``,
            ``recovery``, ``divergence_limit``, ``max_steps``, ``form``, ``every``, and
            ``multipliers=True``: a constrained run's Lagrange multipliers at every point,
            ``sol.multipliers``).

    Returns:
        a :class:`Solution`.

    **The Octave package's call** ``[T, Y] = spectralvarint(odefun, tspan, y0)``: with a
    callable ``model``, ``svi.solve(odefun, tspan, y0)`` integrates y' = odefun(t, y), the
    right-hand side (∂H/∂p, −∂H/∂q + f_H) of Hamilton's equations (forced or not) with
    y = (q, p), by a method on Hamilton's equations (default ``"svi-h"`` with SVI's points;
    ``"sc-h"``, ``"midpoint-h"``, ``"verlet-h"``, ... are the others) with step doubling to
    ``tol`` (default 1e-8; ``adapt="none"`` and ``h`` for fixed steps). ``jac(t, y)`` may give
    the 2N × 2N Jacobian ∂F/∂y (default: central differences; it only steers Newton's method).
    The solution holds the states at every accepted step for ``tspan = (t0, t_end)``, at the
    listed times otherwise: ``T, Y = sol.t, sol.y``. With no H there is no energy to diagnose.

    Raises:
        SviError: the subclass of the failure's kind (bad input, a solve that does not
            converge, ...).
    """
    times = _span_times(t_span)
    if times is not None and len(times) > 2:
        if saveat is not None:
            raise _wrong_type("t_span", "(t0, t_end) when saveat is given", t_span)
        saveat = times
    if y0 is not None:
        y = np.asarray(_reals("y0", np.atleast_1d(y0)), dtype=float)
        if q0 is not None or p0 is not None or v0 is not None:
            raise _wrong_type("y0", "the whole initial state: no q0, v0 or p0 besides it", y0)
        if y.ndim != 1 or y.size % 2 == 1:
            raise _wrong_type("y0", "(q0, p0): one array of 2N numbers", y0)
        q0, p0 = y[: y.size // 2], y[y.size // 2 :]
    if callable(model) and not isinstance(model, (_TextModel, str)):
        if times is None:
            raise _wrong_type("t_span", "(t0, t_end) or [t0, ..., t_end] for odefun", t_span)
        if q0 is None or p0 is None:
            raise _wrong_type("y0", "the initial state (q0, p0) of odefun", y0)
        if jac is not None and not callable(jac):
            raise _wrong_type("jac", "a function of (t, y) returning the 2N × 2N Jacobian", jac)
        max_steps = _count("max_steps", options.pop("max_steps", None))
        unused = {"v0": v0, "saveat": saveat if len(times) == 2 else None, "diagnostics": diagnostics, "params": params}
        unused.update(options)
        given = [name for name, value in unused.items() if value is not None and value is not False] + (["dense"] if dense else [])
        if given:
            raise _wrong_type(given[0], "not an option of odefun (model, t_span, y0, jac, method, h, tol, adapt, max_steps)", unused.get(given[0], dense))
        summary, rows = _call(
            _svi.solve_rhs,
            _flat(model, "odefun", 2 * len(np.atleast_1d(q0)), square=False),
            times,
            _reals("y0", np.concatenate([np.atleast_1d(q0), np.atleast_1d(p0)])),
            jacobian=None if jac is None else _flat(jac, "jac", 2 * len(np.atleast_1d(q0)), square=True),
            method=_text("method", method),
            h=_real("h", h),
            tol=_real("tol", tol),
            adapt=_text("adapt", adapt),
            max_steps=max_steps,
        )
        return Solution(json.loads(summary), rows, None)
    if jac is not None:
        raise _wrong_type("jac", "None: a Jacobian belongs to odefun (a callable model)", jac)
    if times is None:
        t0, t_end = None, _real("t_span", t_span)
    else:
        t0, t_end = times[0], times[-1]
    initial: Dict[str, List[float]] = {}
    if t0 is not None:
        initial["t0"] = [t0]
    for name, value in (("q", q0), ("v", v0), ("p", p0)):
        if value is not None:
            initial[name] = _reals(f"{name}0", np.atleast_1d(value))
    every = _count("every", options.pop("every", None))
    named = dict(method=method, h=h, t_end=t_end, adapt=adapt, tol=tol, diagnostics=diagnostics)
    named["output_times"] = _listed("saveat", _reals("saveat", saveat))
    checked = _shared_options(named, options, "solve")
    callables = _events.split(checked)
    if isinstance(model, _TextModel):
        scene, native = "", model._native()
    else:
        scene, native = _text("model", model), None
    summary, rows, kept = _call(
        _svi.run,
        scene,
        model=native,
        params=None if params is None else {_text("params", k): _real(f"params[{k!r}]", x) for k, x in _mapping("params", params).items()},
        initial=initial or None,
        options=checked,
        trajectory=True,
        every=every,
        progress=False,
        dense=bool(dense),
        events=callables,
    )
    return Solution(json.loads(summary), rows, kept)


def _flat(function: Callable[[float, np.ndarray], Any], name: str, size: int, square: bool) -> Callable[[float, np.ndarray], np.ndarray]:
    """``function`` returning a contiguous float64 array for the Rust core: y' (``size``
    = 2N numbers) as it is; with ``square``, the 2N × 2N Jacobian (rows ∂F_i/∂y) column by
    column. A result of another shape or not of numbers is an :class:`ArgumentTypeError`
    naming ``name`` (raised again when the run ends, as ``function``'s own exceptions are)."""
    shape = (size, size) if square else (size,)

    def flat(t: float, y: np.ndarray) -> np.ndarray:
        value = function(t, y)
        try:
            array = np.asarray(value, dtype=float)
        except (TypeError, ValueError):
            array = None
        if array is None or array.shape != shape and not (not square and array.size == size and array.ndim <= 2):
            raise _wrong_type(f"{name}(t, y)", f"an array of shape {shape}", value)
        return np.ascontiguousarray(array.ravel(order="F" if square else "C"))

    return flat


def _span_times(value: Any) -> Optional[List[float]]:
    """The times of ``t_span``: ``None`` for one number (t_end), else the pair (t0, t_end) or
    the list [t0, ..., t_end] of at least two times."""
    if isinstance(value, (str, bytes)) or np.ndim(value) == 0:
        return None
    times = _reals("t_span", value)
    if times is None or len(times) < 2:
        raise _wrong_type("t_span", "(t0, t_end), [t0, ..., t_end] or t_end", value)
    return times


__all__ = ["Hamiltonian", "Lagrangian", "Solution", "solve"]
