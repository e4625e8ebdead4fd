"""Events given from Python: the ``event`` keyword of :func:`svi.run` and :func:`svi.solve`.

An event is written as text over the model's names, exactly as ``svi run --event`` takes it
(``"pericentre: x*vx + y*vy @up @terminal"``), or as an :class:`Event` whose function is text
or a Python callable ``g(t, q, v)`` of a float and two NumPy arrays returning a float. Text
events are parsed and evaluated in Rust; a callable is called from the run with the GIL held,
at every step's end and interior samples and during the root find, so it costs a Python call
each time (a text event none).
"""

from __future__ import annotations

from typing import Any, Callable, List, Optional, Tuple, Union

#: The directions of crossings an event counts.
DIRECTIONS = ("up", "down", "both")


class Event:
    """An event: the times at which ``g(t, q, v)`` crosses zero, located on each step's own
    polynomial and refined on the method's exact steps.

    Args:
        g: the function, as text over the model's coordinate names, their velocities (``v`` and
            the name), ``t`` and the parameters (``"x*vx + y*vy"``), or a callable
            ``g(t, q, v) -> float`` (``q`` and ``v`` NumPy arrays).
        name: its name in the results (default: a callable's ``__name__``, else ``event1``,
            ``event2``, … by position among the text events and ``callable1``, … among the
            callables).
        direction: ``"up"`` (g rises through 0), ``"down"`` or ``"both"`` (default).
        terminal: whether the first crossing ends the run (with status ok and
            ``terminal_event`` naming it).
    """

    def __init__(
        self,
        g: Union[str, Callable[..., float]],
        name: Optional[str] = None,
        direction: str = "both",
        terminal: bool = False,
    ) -> None:
        if not isinstance(g, str) and not callable(g):
            raise TypeError(f"Event: g must be text or a callable g(t, q, v), not {type(g).__name__}")
        if name is not None and not isinstance(name, str):
            raise TypeError(f"Event: name must be a string, not {type(name).__name__}")
        if direction not in DIRECTIONS:
            raise ValueError(f"Event: direction must be one of {', '.join(DIRECTIONS)}, not {direction!r}")
        if not isinstance(terminal, bool):
            raise TypeError(f"Event: terminal must be True or False, not {type(terminal).__name__}")
        self.g = g
        self.name = name
        self.direction = direction
        self.terminal = terminal

    def __repr__(self) -> str:
        return (
            f"Event({self.g!r}, name={self.name!r}, direction={self.direction!r}, "
            f"terminal={self.terminal!r})"
        )

    def _text(self) -> str:
        """The event as the argument of ``svi run --event`` (a text event only)."""
        name = "" if self.name is None else f"{self.name}: "
        terminal = " @terminal" if self.terminal else ""
        return f"{name}{self.g} @{self.direction}{terminal}"


def events(option: str, value: Any) -> Optional[List[Union[str, Event]]]:
    """The check of a repeatable text option (``event``): one item or a list of items, each
    text (the flag's argument), an :class:`Event` or a callable; ``None`` kept."""
    if value is None:
        return None
    items = [value] if isinstance(value, (str, Event)) or callable(value) else value
    try:
        items = list(items)
    except TypeError:
        raise TypeError(f"{option} must be text, an Event, a callable or a list of them, not {type(value).__name__}") from None
    checked: List[Union[str, Event]] = []
    for item in items:
        if isinstance(item, (str, Event)):
            checked.append(item)
        elif callable(item):
            checked.append(Event(item))
        else:
            raise TypeError(f"{option} items must be text, an Event or a callable, not {type(item).__name__}")
    return checked


#: An event given as a callable, as the native module takes it: (name, direction, terminal, g).
NativeEvent = Tuple[str, str, bool, Callable[..., float]]


def split(options: dict) -> List[NativeEvent]:
    """Replace the events in ``options`` by their texts and return the callables' events
    (named by their ``__name__``, or ``callable1``, … by position)."""
    items = options.pop("event", None)
    if items is None:
        return []
    texts: List[str] = []
    callables: List[NativeEvent] = []
    for item in items:
        if isinstance(item, str):
            texts.append(item)
        elif isinstance(item.g, str):
            texts.append(item._text())
        else:
            default = getattr(item.g, "__name__", "<lambda>")
            name = item.name or (default if default.isidentifier() else f"callable{len(callables) + 1}")
            callables.append((name, item.direction, item.terminal, item.g))
    if texts:
        options["event"] = texts
    return callables
