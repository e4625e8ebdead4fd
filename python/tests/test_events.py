"""Events, sections and chaos indicators from Python: the keywords of ``svi run``'s flags
(``event``, ``section``, ``indicators``) give the numbers of the command line."""

import math

import svi


def test_kepler_pericentres_are_events_at_two_pi_k():
    result = svi.run("kepler", event="pericentre: q1*vq1 + q2*vq2 @up", t_end=20.0)
    times = [event["t"] for event in result.summary["events"]]
    assert len(times) == 3
    for k, t in enumerate(times, start=1):
        assert abs(t - 2 * math.pi * k) < 1e-8


def test_a_section_and_the_indicators_of_the_chaotic_henon_heiles_orbit():
    section = svi.run("henon-heiles", section="x=0,vx>0").summary["section"]
    assert section["axes"] == ["q_y", "v_y"] and section["points"] > 250
    summary = svi.run("henon-heiles", indicators=["megno", "spectrum"]).summary
    assert abs(sum(summary["lyapunov"])) < 1e-10
    assert summary["lyapunov"][0] > 0.03 and summary["megno"] > 20


def test_a_bad_section_is_bad_input_naming_it():
    try:
        svi.run("henon-heiles", section="z=0")
    except svi.SviError as error:
        assert "'z'" in str(error)
    else:
        raise AssertionError("a section on an unknown coordinate ran")


def test_events_as_callables_are_located_where_their_text_twins_are():
    # The pericentre, r·ṙ = 0 rising, of Kepler e = 0.5 (period 2π): as text, as a
    # callable of NumPy arrays, and a text event with its options as an svi.Event.
    def pericentre(t, q, v):
        return q[0] * v[0] + q[1] * v[1]

    result = svi.run(
        "kepler",
        t_end=20.0,
        trajectory=False,
        event=[
            "text: q1*vq1 + q2*vq2 @up",
            svi.Event(pericentre, direction="up"),
            svi.Event("q1*vq1 + q2*vq2", name="wrapped", direction="up"),
        ],
    )
    times = {}
    for event in result.summary["events"]:
        times.setdefault(event["name"], []).append(event["t"])
    assert sorted(times) == ["pericentre", "text", "wrapped"]
    for name in times:
        assert len(times[name]) == 3
        for k, t in enumerate(times[name], start=1):
            assert abs(t - 2 * math.pi * k) < 1e-8, (name, t)
    assert times["pericentre"] == times["text"]


def test_a_terminal_callable_ends_the_run_and_solve_takes_callables():
    # Kepler e = 0.5 starts at the pericentre (1/2, 0) moving up: y falls through 0 at the
    # apocentre, half a period later.
    result = svi.run(
        "kepler",
        t_end=20.0,
        event=svi.Event(lambda t, q, v: q[1], direction="down", terminal=True),
    )
    assert result.summary["terminal_event"] == "callable1"
    assert abs(result.t[-1] - math.pi) < 1e-8
    solution = svi.solve("kepler", 20.0, event=lambda t, q, v: q[1])
    assert [round(e["t"] / math.pi) for e in solution.summary["events"]] == list(range(1, 7))


def test_a_callable_that_raises_or_returns_no_number_fails_the_run_with_its_error():
    def broken(t, q, v):
        raise ZeroDivisionError("broken event")

    for event, error, says in [
        (broken, ZeroDivisionError, "broken event"),
        (lambda t, q, v: "up", TypeError, "event 'callable1': g(t, q, v) returned str"),
    ]:
        try:
            svi.run("kepler", t_end=1.0, event=event)
        except error as raised:
            assert says in str(raised)
        else:
            raise AssertionError(f"{event} ran")
    for bad in [42, [None]]:
        try:
            svi.run("kepler", t_end=1.0, event=bad)
        except TypeError as raised:
            assert "event" in str(raised)
        else:
            raise AssertionError(f"event={bad!r} ran")
    try:
        svi.ensemble("kepler", params={"e": [0.1, 0.2]}, t_end=1.0, event=broken)
    except TypeError as raised:
        assert "callables are events of svi.run" in str(raised)
    else:
        raise AssertionError("an ensemble took a callable event")
