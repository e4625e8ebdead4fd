"""The Python doors of a scene give the numbers of ``svi run SCENE --json``, bit for bit: svi.run,
svi.solve (the scene's model by name, or the same Lagrangian written with svi.Lagrangian),
svi.ensemble (one member: the scene alone, or a grid whose one member has the scene's values)
and svi.bench (the scene's method at the scene's step: steps = (t_end − t0)/h). Only wall
times differ. The binary's JSON is read with Python's exact float parser.

svi.bench reports per point the step, the steps taken, the final error, the energy and
momentum errors, the evaluations and iterations, not the state; its final error is the run's
``solution_error_final`` (‖q(t_end) − q_exact(t_end)‖) for a model with an exact solution. The
command line's doors are held to the same numbers by cli/tests/front_doors.rs."""

import json
import math
import subprocess

import pytest

import svi

from svi_binary import svi_binary

#: The fields of a summary that are the same computation whatever the door (not ``seconds``).
FIELDS = [
    "q",
    "v",
    "p",
    "t_end",
    "steps",
    "energy_initial",
    "energy_final",
    "energy_error_max",
    "energy_error_final",
    "energy_scale",
    "momentum_error_max",
    "solution_error_max",
    "solution_error_final",
    "iterations",
    "evaluations",
    "factorizations",
    "retries",
]


def cli_run(scene, *args):
    """``svi run SCENE ARGS --json`` as a dict."""
    done = subprocess.run([svi_binary(), "run", scene, *args, "--json"], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


def assert_same_summary(summary, reference):
    """Every field of the computation, exactly (``None`` where both have none)."""
    for field in FIELDS:
        assert summary.get(field) == reference.get(field), field


def assert_row_is_the_run(table, reference):
    """The one row of an ensemble's table (a dict of columns) is the run."""
    assert table["member"].tolist() == [0]
    assert table["status"].tolist() == ["ok"]
    for i, name in enumerate(reference.get("coordinates") or []):
        for field in ("q", "v", "p"):
            assert table[f"{field}_{name}"][0] == reference[field][i], (field, name)
    for field in ["t_end", "steps", "energy_initial", "energy_final", "energy_error_max", "energy_scale", "iterations", "evaluations", "retries"]:
        assert table[field][0] == reference[field], field
    for field in ["momentum_error_max", "solution_error_max"]:
        value = table[field][0]
        if reference[field] is None:
            assert value != value, field  # NaN: an empty cell
        else:
            assert value == reference[field], field


def assert_record_is_the_run(records, reference, final_error=None):
    """The one record of a bench is the run: steps, errors, evaluations, iterations."""
    assert len(records["method"]) == 1
    for field in ["steps", "evaluations", "iterations"]:
        assert records[field][0] == reference[field], field
    assert records["h"][0] == reference["h"]
    assert records["energy_error_max"][0] == reference["energy_error_max"]
    momentum = records["momentum_error_max"][0]
    if reference.get("momentum_error_max") is None:
        assert momentum is None or momentum != momentum
    else:
        assert momentum == reference["momentum_error_max"]
    expected = reference["solution_error_final"] if final_error is None else final_error
    assert records["final_error"][0] == expected


def bench(scene, method, steps, **options):
    return svi.bench(scene, methods=method, steps=[steps], batches=1, min_batch=0, as_frame=False, **options)


def test_kepler_by_svi_is_the_same_run_through_every_python_door():
    diagnostics = ["energy", "momentum", "solution"]
    reference = cli_run("kepler", "--t-end", "20", "--diagnostics", ",".join(diagnostics))
    assert (reference["method"], reference["points"], reference["h"], reference["steps"]) == ("svi", 6, 0.2, 100)

    result = svi.run("kepler", t_end=20.0, diagnostics=diagnostics)
    assert_same_summary(result.summary, reference)
    assert result.q[-1].tolist() == reference["q"] and result.p[-1].tolist() == reference["p"]
    for solution in (
        svi.solve("kepler", 20.0, diagnostics=diagnostics),
        svi.solve("kepler", (0.0, 20.0), method="svi:6/12", h=0.2, diagnostics=diagnostics),
        # The scene's initial state given explicitly: the pericentre of e = 0.5.
        svi.solve("kepler", 20.0, q0=[0.5, 0.0], v0=[0.0, math.sqrt(3.0)], diagnostics=diagnostics),
    ):
        assert_same_summary(solution.summary, reference)

    for params in (None, {"e": [0.5]}):
        table = svi.ensemble("kepler", params=params, t_end=20.0, diagnostics=diagnostics, as_frame=False)
        assert_row_is_the_run(table, reference)

    assert_record_is_the_run(bench("kepler", "svi:6/12", 100, t_end=20.0), reference)


def test_kepler_written_as_a_lagrangian_is_the_text_scene():
    reference = cli_run("kepler-text", "--t-end", "20")
    kepler = svi.Lagrangian("0.5*(vx^2 + vy^2) + mu/sqrt(x^2 + y^2)", q=["x", "y"], params={"mu": 1.0}, symmetries=[["-y", "x"]])
    solution = svi.solve(kepler, 20.0, q0=[0.5, 0.0], v0=[0.0, 1.7320508075688772], method="svi:6", h=0.2)
    assert_same_summary(solution.summary, reference)
    table = svi.ensemble(
        kepler, q0=[0.5, 0.0], v0=[0.0, 1.7320508075688772], method="svi:6", h=0.2, t_end=20.0, diagnostics=["energy", "momentum"], as_frame=False
    )
    assert_row_is_the_run(table, reference)
    assert_same_summary(svi.run("kepler-text", t_end=20.0).summary, reference)


def test_the_oscillator_by_collocation_from_a_momentum_is_the_same_run():
    diagnostics = ["energy", "solution"]
    reference = cli_run("oscillator", "--method", "sc:9", "--t-end", "20", "--diagnostics", ",".join(diagnostics))
    assert reference["steps"] == 20
    assert_same_summary(svi.run("oscillator", "sc:9", t_end=20.0, diagnostics=diagnostics).summary, reference)
    solution = svi.solve("oscillator", 20.0, q0=[0.0], p0=[1.0], method="sc:9", h=1.0, diagnostics=diagnostics)
    assert_same_summary(solution.summary, reference)
    table = svi.ensemble("oscillator", method="sc:9", t_end=20.0, diagnostics=diagnostics, as_frame=False)
    assert_row_is_the_run(table, reference)
    assert_record_is_the_run(bench("oscillator", "sc:9", 20, t_end=20.0), reference)


def test_a_scene_with_recovery_is_the_same_run():
    reference = cli_run("kepler-recovery", "--t-end", "11")
    assert reference["steps"] == 100 and reference["retries"] > 0
    result = svi.run("kepler-recovery", t_end=11.0)
    assert_same_summary(result.summary, reference)
    # The same failed health check (a step too coarse for the pericentre).
    assert result.warnings == reference["warnings"] != []
    table = svi.ensemble("kepler-recovery", t_end=11.0, diagnostics=["energy", "momentum"], as_frame=False)
    assert_row_is_the_run(table, reference)
    assert_record_is_the_run(bench("kepler-recovery", "svi:6/12", 100, t_end=11.0), reference)


def test_a_chain_is_the_same_run():
    reference = cli_run("fput", "--t-end", "5", "--diagnostics", "energy")
    assert reference["steps"] == 50
    assert_same_summary(svi.run("fput", t_end=5.0, diagnostics=["energy"]).summary, reference)
    assert_same_summary(svi.solve("fput", 5.0, diagnostics=["energy"]).summary, reference)
    for params in (None, {"n": [32]}):
        table = svi.ensemble("fput", params=params, t_end=5.0, diagnostics=["energy"], as_frame=False)
        assert_row_is_the_run(table, reference)
    records = bench("fput", "svi:6/12", 50, t_end=5.0)
    for field in ["steps", "evaluations", "iterations", "energy_error_max", "h"]:
        assert records[field][0] == reference[field], field
