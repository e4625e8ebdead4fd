"""Ctrl-C during a run: the run stops between steps, `KeyboardInterrupt` is raised, and the
next run works. The signal is sent by a timer thread to this process, as a terminal sends it."""

import os
import signal
import threading
import time

import pytest

import svi

pytestmark = pytest.mark.skipif(os.name != "posix", reason="sends SIGINT to the process")

# A run of about a minute (10⁸ Kepler steps) unless it is stopped.
LONG = dict(t_end=1.0e6, h=1.0e-2)
SENT_AFTER = 0.3
# Signals are looked for every 50 ms and a run stops within 64 steps.
STOPPED_WITHIN = 2.0


@pytest.fixture(autouse=True)
def python_handles_ctrl_c():
    """Python's own SIGINT handler, whatever the process inherited: a shell starts background
    jobs (CI's) with SIGINT ignored, and Python then installs no handler."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, previous)


def interrupt_after(seconds):
    timer = threading.Timer(seconds, os.kill, (os.getpid(), signal.SIGINT))
    timer.start()
    return timer


def test_ctrl_c_stops_a_solve_between_steps_and_the_next_run_works():
    start = time.perf_counter()
    timer = interrupt_after(SENT_AFTER)
    with pytest.raises(KeyboardInterrupt):
        svi.solve("kepler", LONG["t_end"], h=LONG["h"], saveat=[LONG["t_end"]])
    timer.join()
    assert time.perf_counter() - start < SENT_AFTER + STOPPED_WITHIN
    sol = svi.solve("kepler", 1.0, h=0.01)
    assert sol.steps == 100 and sol.summary["status"] == "ok"


def test_ctrl_c_stops_a_scene_run_and_an_ensemble():
    for call in (
        lambda: svi.run("kepler", **LONG, diagnostics=["none"], trajectory=False),
        lambda: svi.ensemble("kepler", params={"e": [0.5, 0.6, 0.7]}, threads=1, as_frame=False, **LONG),
    ):
        start = time.perf_counter()
        timer = interrupt_after(SENT_AFTER)
        with pytest.raises(KeyboardInterrupt):
            call()
        timer.join()
        assert time.perf_counter() - start < SENT_AFTER + STOPPED_WITHIN


def test_ctrl_c_stops_a_constrained_run():
    # RATTLE on the spherical pendulum: about 10⁸ steps unless it is stopped.
    start = time.perf_counter()
    timer = interrupt_after(SENT_AFTER)
    with pytest.raises(KeyboardInterrupt):
        svi.run("spherical-pendulum", **LONG, diagnostics=["none"], trajectory=False)
    timer.join()
    assert time.perf_counter() - start < SENT_AFTER + STOPPED_WITHIN
    assert svi.run("spherical-pendulum", t_end=1.0, h=0.01).summary["status"] == "ok"
