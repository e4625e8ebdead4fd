"""Models and solutions: :class:`Lagrangian` written as text (or SymPy), :func:`solve` and the
:class:`Solution` it returns, evaluated at any time by the method's own step polynomials."""

from __future__ import annotations

import json
import re
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from . import _events, _svi

# The helpers of the package (argument checks, errors, the result object): this module is
# imported at the end of ``svi/__init__.py``, once they exist.
from . import (  # noqa: E402
    Result,
    _call,
    _count,
    _exact,
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


class Lagrangian:
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

    def _native(
        self,
    ) -> Tuple[str, List[str], Optional[List[str]], Optional[List[List[str]]], Optional[List[str]], Dict[str, float]]:
        return (self.expr, self.q, self.forces, self.symmetries, self.constraints, self.params)

    def __repr__(self) -> str:
        constraints = "" if self.constraints is None else f", constraints={self.constraints!r}"
        return f"Lagrangian({self.expr!r}, q={self.q!r}, params={self.params!r}{constraints})"


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
    def span(self) -> Optional[Tuple[float, float]]:
        """The times the step polynomials cover: (t0, t_end)."""
        return None if self._dense is None else self._dense.span()


def solve(
    model: Union[Lagrangian, str],
    t_span: Union[float, Tuple[float, float], Sequence[float]],
    *,
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
        model: a :class:`Lagrangian`, or a zoo model's or built-in scene's name (:func:`models`,
            :func:`scenes`), whose defaults fill what is not given.
        t_span: ``(t0, t_end)``, or ``t_end`` (from the model's t0, else 0).
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

    Raises:
        SviError: the subclass of the failure's kind (bad input, a solve that does not
            converge, ...).
    """
    if _is_span_pair(t_span):
        t0, t_end = (_real("t_span", x) for x in t_span)
    else:
        t0, t_end = None, _real("t_span", t_span)
    initial: Dict[str, List[float]] = {}
    if t0 is not None:
        initial["t0"] = [t0]
    for name, value in (("q", q0), ("v", v0), ("p", p0)):
        if value is not None:
            initial[name] = _reals(f"{name}0", np.atleast_1d(value))
    every = _count("every", options.pop("every", None))
    named = dict(method=method, h=h, t_end=t_end, adapt=adapt, tol=tol, diagnostics=diagnostics)
    named["output_times"] = _reals("saveat", saveat)
    checked = _shared_options(named, options, "solve")
    callables = _events.split(checked)
    if isinstance(model, Lagrangian):
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


def _is_span_pair(value: Any) -> bool:
    """Whether ``value`` is a pair (t0, t_end) rather than one number."""
    if isinstance(value, (str, bytes)) or np.ndim(value) == 0:
        return False
    if len(value) != 2:
        raise _wrong_type("t_span", "(t0, t_end) or t_end", value)
    return True


__all__ = ["Lagrangian", "Solution", "solve"]
