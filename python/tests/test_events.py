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
