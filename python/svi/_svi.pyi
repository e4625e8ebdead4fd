"""Type stubs of the native module svi._svi (the Rust core; use the functions of ``svi``)."""

from typing import Callable, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

#: A value of an option of ``svi run`` given by name (checked by ``svi`` for its kind).
OptionValue = Union[int, float, str, List[float], List[str]]

#: A model written as text: ("lagrangian" or "hamiltonian", the expression, coordinates, forces,
#: symmetries, constraints, parameters).
TextModel = Tuple[
    str, str, List[str], Optional[List[str]], Optional[List[List[str]]], Optional[List[str]], Dict[str, float]
]

class Failure(Exception):
    """A failed call; its one argument is the JSON text of the failure object."""

class Dense:
    """Every step's polynomial of a run (``svi.Solution``'s dense output)."""

    def evaluate(self, times: np.ndarray) -> List[np.ndarray]:
        """(q, v, p) at ``times``, each len(times) × dimension numbers row by row."""
    def span(self) -> Optional[Tuple[float, float]]:
        """(first step's start, last step's end)."""
    def dimension(self) -> int:
        """The number of coordinates."""

def run(
    scene: str,
    *,
    model: Optional[TextModel] = None,
    params: Optional[Dict[str, float]] = None,
    initial: Optional[Dict[str, List[float]]] = None,
    options: Optional[Dict[str, OptionValue]] = None,
    trajectory: bool = True,
    every: Optional[int] = None,
    progress: bool = False,
    dense: bool = False,
    events: List[Tuple[str, str, bool, Callable[..., float]]] = [],
) -> Tuple[str, Optional[Tuple[List[str], np.ndarray]], Optional[Dense]]:
    """Run a scene (or ``model``, a text model) as ``svi run`` does: the JSON summary, the
    trajectory's columns and numbers (row by row), with ``dense`` every step's polynomial;
    ``events`` are events given as callables (name, direction, terminal, g(t, q, v))."""

def gradient(
    scene: str,
    loss: Callable[[int, float, np.ndarray, np.ndarray], Tuple[float, List[float], List[float]]],
    *,
    params: Optional[Dict[str, float]] = None,
    initial: Optional[Dict[str, List[float]]] = None,
    options: Optional[Dict[str, OptionValue]] = None,
    checkpoints: Optional[int] = None,
) -> str:
    """The gradient of a loss over a scene's fixed-step run by the discrete adjoint, with
    respect to the ``sensitivity`` names of ``options``: its JSON (``value``, ``columns``,
    ``gradient``, ``peak_stored``, ``peak_bytes``)."""

def solve_rhs(
    odefun: Callable[[float, np.ndarray], object],
    times: List[float],
    y0: List[float],
    *,
    jacobian: Optional[Callable[[float, np.ndarray], object]] = None,
    method: Optional[str] = None,
    h: Optional[float] = None,
    tol: Optional[float] = None,
    adapt: Optional[str] = None,
    max_steps: Optional[int] = None,
) -> Tuple[str, Tuple[List[str], np.ndarray]]:
    """The Octave package's call: y' = odefun(t, y), y = (q, p), from y0 over ``times`` by a
    method on Hamilton's equations; the JSON summary and the rows (t, q, p)."""

def ensemble(
    scene: str,
    *,
    model: Optional[TextModel] = None,
    base: Optional[Dict[str, List[float]]] = None,
    params: Sequence[str] = ...,
    initial: Sequence[str] = ...,
    random: Optional[int] = None,
    seed: int = 0,
    start: int = 0,
    stop: Optional[int] = None,
    threads: int = 0,
    options: Optional[Dict[str, OptionValue]] = None,
) -> Tuple[int, List[str], List[List[object]]]:
    """Run members ``start..stop`` of an ensemble: (member count, columns, rows)."""

def options() -> List[Tuple[str, str]]:
    """The options of ``svi run`` the calls take (in ``options``), each with the kind of its
    value: ``real``, ``count``, ``text``, ``reals`` or ``names``."""

def models() -> str:
    """The zoo models on ℝᴺ, as JSON."""

def scenes() -> List[Tuple[str, str]]:
    """The built-in scenes: (name, description)."""

def version() -> str:
    """The svi version."""

def stability(args: List[str]) -> Tuple[str, Optional[str]]:
    """``svi stability ARGS``: the CSV of the points and, for a range, the regions as JSON."""

def bench(args: List[str]) -> str:
    """``svi bench ARGS``: the work–precision records as JSON."""
