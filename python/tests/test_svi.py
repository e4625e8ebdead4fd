"""The svi Python package against the svi binary: the same numbers digit for digit (the binary's
JSON is read with Python's exact float parser), errors as exceptions with the failure object's
fields, ensembles as tables, and a Dask cluster that returns the local table."""

import json
import math
import subprocess

import numpy as np
import pytest

import svi

from svi_binary import svi_binary


def cli(*args):
    """`svi ARGS` as (exit status, stdout, stderr)."""
    done = subprocess.run([svi_binary(), *args], capture_output=True, text=True, timeout=600)
    return done.returncode, done.stdout, done.stderr


def cli_json(*args):
    status, stdout, stderr = cli(*args)
    assert status == 0, stderr
    return json.loads(stdout)


def test_run_kepler_matches_the_binary_to_the_last_digit():
    result = svi.run("kepler")
    reference = cli_json("run", "kepler", "--json")
    assert result.q[-1].tolist() == reference["q"]
    assert result.v[-1].tolist() == reference["v"]
    assert result.p[-1].tolist() == reference["p"]
    assert result.summary["q"] == reference["q"]
    for field in ["steps", "iterations", "evaluations", "energy_error_max", "energy_final", "momentum_error_max", "solution_error_max"]:
        assert result.summary[field] == reference[field], field
    # The trajectory: every step, from t0 to t_end.
    assert result.t.shape == (10001,)
    assert result.q.shape == (10001, 2)
    assert result.t[0] == 0.0 and result.t[-1] == 2000.0
    assert result.steps == 10000
    assert "energy_error_max" in dir(result)


def test_the_readme_command_prints_the_binarys_digits():
    import re
    import sys

    printed = subprocess.run(
        [sys.executable, "-c", "import svi; print(svi.run('kepler').q[-1])"],
        capture_output=True, text=True, check=True, cwd="/",
    ).stdout.strip()
    _, stdout, _ = cli("run", "kepler", "--json")
    digits = re.search(r'"q":\[([^\]]*)\]', stdout).group(1).split(",")
    assert printed == "[" + ", ".join(digits) + "]"


def test_overrides_method_params_initial_and_output_times():
    result = svi.run("kepler", method="svi:7/6", h=0.1, t_end=5.0, params={"e": 0.6}, diagnostics=["energy"])
    reference = cli_json(
        "run", "kepler", "--method", "svi:7/6", "--h", "0.1", "--t-end", "5", "--param", "e=0.6",
        "--diagnostics", "energy", "--json",
    )
    assert result.q[-1].tolist() == reference["q"]
    assert (result.points, result.quadrature, result.parameters) == (7, 6, {"e": 0.6, "phase": 0.0})
    assert result.momentum_error_max is None
    # The oscillator from q0 = 0, v0 = 1: q(t) = sin t.
    result = svi.run("oscillator", initial={"q": [0.0], "v": [1.0]}, output_times=[1.0, 2.5], t_end=3.0)
    assert result.t.tolist() == [0.0, 1.0, 2.5]
    assert np.allclose(result.q[:, 0], np.sin(result.t), atol=1e-12)
    assert [point["t"] for point in result.outputs] == [1.0, 2.5]
    # A zoo model by name, with its defaults; and a scene given as text.
    assert svi.run("pendulum", t_end=1.0).model == "pendulum"
    text = 'model = "oscillator"\n[run]\nh = 0.5\nt_end = 2.0\n'
    assert svi.run(text).steps == 4
    assert svi.run("kepler", t_end=4.0, every=5).q.shape == (5, 2)
    assert svi.run("kepler", t_end=4.0, trajectory=False).q is None


def test_a_reparametrised_run_takes_its_monitor_and_matches_the_binary():
    # Kepler e = 0.9 over T = 2000 (about 318 orbits), fixed steps 0.3 in τ with dt = |q| dτ:
    # the final position within 1e-9 of the exact orbit (tests/reparam.rs, docs/guide/src/adaptivity.md).
    arguments = dict(method="svi:9/8", h=0.3, params={"e": 0.9}, adapt="reparam", diagnostics=["solution"])
    result = svi.run("kepler", monitor="sundman:1", trajectory=False, **arguments)
    reference = cli_json(
        "run", "kepler", "--method", "svi:9/8", "--h", "0.3", "--param", "e=0.9", "--adapt", "reparam",
        "--monitor", "sundman:1", "--diagnostics", "solution", "--json",
    )
    assert result.summary["q"] == reference["q"]
    assert (result.summary["adapt"], result.summary["monitor"]) == ("reparam", "sundman:1")
    assert result.solution_error_final < 1e-9
    # The default monitor (sundman:1.5) is another run; a malformed one is bad input.
    assert svi.run("kepler", trajectory=False, **arguments).summary["q"] != reference["q"]
    with pytest.raises(svi.InvalidInputError) as caught:
        svi.run("kepler", monitor="sundman:x", **arguments)
    assert "monitor" in caught.value.message


def test_errors_are_exceptions_with_the_failure_objects_fields():
    with pytest.raises(svi.InvalidParameterError) as caught:
        svi.run("kepler", params={"e": 1.2})
    error = caught.value
    status, stdout, _ = cli("run", "kepler", "--param", "e=1.2", "--json")
    reference = json.loads(stdout)["error"]
    assert status == 2 and error.bad_input
    assert (error.kind, error.message, error.step, error.t) == (reference["kind"], reference["message"], None, None)
    assert isinstance(error, svi.SviError) and isinstance(error, ValueError)

    with pytest.raises(svi.InvalidInputError) as caught:
        svi.run("no-such-scene")
    assert caught.value.kind == "invalid_input"
    assert "no built-in scene" in caught.value.message

    # A run that fails after it started: the step, the time and the partial summary.
    with pytest.raises(svi.SviError) as caught:
        svi.run("kepler", params={"e": 0.95}, h=1.0, t_end=50.0)
    error = caught.value
    status, stdout, _ = cli("run", "kepler", "--param", "e=0.95", "--h", "1", "--t-end", "50", "--json")
    reference = json.loads(stdout)
    assert status == 1 and not error.bad_input
    assert error.kind == reference["error"]["kind"]
    assert (error.step, error.t) == (reference["error"]["step"], reference["error"]["t"])
    assert error.summary["q"] == reference["q"]
    assert error.summary["status"] == "failed"

    with pytest.raises(svi.InvalidInputError):
        svi.run("kepler", adapt="sometimes")

    # A run out of its step budget: the typed error, as from the command line.
    with pytest.raises(svi.TooManyStepsError) as caught:
        svi.run("kepler", params={"e": 0.9}, adapt="step", tol=1e-10, t_end=100.0, max_steps=60)
    status, stdout, _ = cli(
        "run", "kepler", "--param", "e=0.9", "--adapt", "step", "--tol", "1e-10", "--t-end", "100",
        "--max-steps", "60", "--json",
    )
    reference = json.loads(stdout)["error"]
    assert status == 1 and reference["kind"] == "too_many_steps" == caught.value.kind
    assert caught.value.step == 60 == reference["step"] and caught.value.t == reference["t"]


def test_models_and_scenes():
    names = [model["name"] for model in svi.models()]
    assert "kepler" in names and "double-pendulum" in names
    kepler = next(model for model in svi.models() if model["name"] == "kepler")
    assert kepler["coordinates"] == ["q1", "q2"]
    assert "kepler" in svi.scenes()


def test_ensemble_rows_are_the_single_runs_and_a_failure_is_recorded():
    table = svi.ensemble("kepler", params={"e": [0.1, 0.3, 0.5, 1.2]}, t_end=20.0, as_frame=False)
    assert table["member"].tolist() == [0, 1, 2, 3]
    assert table["status"].tolist() == ["ok", "ok", "ok", "invalid_parameter"]
    assert math.isnan(table["q_q1"][3])
    assert "outside [0, 1)" in table["error"][3]
    for i, e in enumerate([0.1, 0.3, 0.5]):
        single = svi.run("kepler", params={"e": e}, t_end=20.0, diagnostics=["energy"], trajectory=False)
        assert [table["q_q1"][i], table["q_q2"][i]] == single.summary["q"]
        assert table["energy_error_max"][i] == single.energy_error_max
        assert table["steps"][i] == single.steps


def test_ensemble_matches_the_binarys_table():
    frame = svi.ensemble("kepler", params={"e": (0.0, 0.8, 5)}, t_end=10.0)
    import pandas

    assert isinstance(frame, pandas.DataFrame)
    status, stdout, stderr = cli("ensemble", "kepler", "--param", "e=0:0.8:5", "--t-end", "10")
    assert status == 0, stderr
    lines = stdout.splitlines()
    assert lines[0].split(",") == list(frame.columns)
    for line, (_, row) in zip(lines[1:], frame.iterrows()):
        for text, value in zip(line.split(","), row):
            if text == "":
                assert value == "" or (isinstance(value, float) and math.isnan(value))
            elif isinstance(value, str):
                assert text == value
            else:
                assert float(text) == value


def test_random_draws_and_initial_grids():
    drawn = svi.ensemble("kepler", params={"e": (0.0, 0.8)}, random=20, seed=3, t_end=5.0, as_frame=False)
    again = svi.ensemble("kepler", params={"e": (0.0, 0.8)}, random=20, seed=3, t_end=5.0, as_frame=False, threads=1)
    assert drawn["e"].tolist() == again["e"].tolist()
    assert drawn["q_q1"].tolist() == again["q_q1"].tolist()
    grid = svi.ensemble("double-pendulum", initial={"q.alpha1": (-1.0, 1.0, 3), "q.alpha2": [0.0, 0.5]}, t_end=0.5, as_frame=False)
    assert len(grid["member"]) == 6
    assert grid["q.alpha1"].tolist() == [-1.0, -1.0, 0.0, 0.0, 1.0, 1.0]
    with pytest.raises(svi.InvalidInputError) as caught:
        svi.ensemble("kepler", params={"x": [1.0]})
    assert "no parameter 'x'" in caught.value.message
    with pytest.raises(svi.InvalidInputError):
        svi.ensemble("kepler", params={"e": (0.9, 0.1, 3)})


def test_a_dask_cluster_returns_the_local_table():
    distributed = pytest.importorskip("dask.distributed")
    kwargs = dict(params={"e": [0.0, 0.2, 0.4, 0.6, 0.8, 1.2]}, t_end=20.0, as_frame=False)
    local = svi.ensemble("kepler", **kwargs)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        with distributed.Client(cluster) as client:
            remote = svi.ensemble("kepler", client=client, chunk_size=2, **kwargs)
    assert list(remote) == list(local)
    for name in local:
        a, b = local[name], remote[name]
        if a.dtype == object:
            assert a.tolist() == b.tolist(), name
        else:
            assert np.array_equal(a, b, equal_nan=True), name
    assert remote["status"].tolist()[-1] == "invalid_parameter"


def test_stability_and_bench():
    points = svi.stability("svi:5/4", z=[0.5, 2.0], as_frame=False)["points"]
    status, stdout, _ = cli("stability", "--method", "svi:5/4", "--z", "0.5,2")
    assert status == 0
    rows = [line.split(",") for line in stdout.strip().splitlines()[1:]]
    assert points["rho"].tolist() == [float(row[1]) for row in rows]
    report = svi.stability("verlet", z_min=0.1, z_max=5.0, samples=50)
    assert report["stable"] and report["stable"][0][1] == pytest.approx(4.0, rel=1e-9)
    records = svi.bench("kepler", methods="verlet", steps=[200, 400], t_end=2.0, batches=1, min_batch=0, as_frame=False)
    assert records["method"].tolist() == ["verlet", "verlet"]
    assert records["final_error"][1] < records["final_error"][0]
    with pytest.raises(svi.InvalidInputError):
        svi.stability("no-such-method", z=[1.0])


def harmonic_chain(n, indexed):
    """n unit masses between two walls joined by unit springs, as a scene's text: an indexed sum
    (local terms, run by the sparse path) or n named coordinates (one Lagrangian of run-time
    size). From q_i = a sin(πi/(n+1)), v = 0 it moves in its lowest mode:
    q_i(t) = a sin(πi/(n+1)) cos(ωt) with ω = 2 sin(π/(2(n+1)))."""
    if indexed:
        model = (
            'lagrangian = "sum(i, 1, n, 0.5*vq[i]^2) - sum(i, 0, n, 0.5*(q[i+1] - q[i])^2)"\n'
            'coordinates = ["q[1..n]"]\nboundary = "fixed"\n'
            f"[parameters]\nn = {n}\na = 1.0\n"
            '[initial]\nq = "a*sin(pi*i/(n+1))"\nv = "0"\n'
        )
    else:
        kinetic = " + ".join(f"vx{i}^2" for i in range(1, n + 1))
        springs = " + ".join(["x1^2", *(f"(x{i + 1} - x{i})^2" for i in range(1, n)), f"x{n}^2"])
        start = [math.sin(math.pi * i / (n + 1)) for i in range(1, n + 1)]
        model = (
            f'lagrangian = "0.5*({kinetic}) - 0.5*({springs})"\n'
            f"coordinates = {json.dumps([f'x{i}' for i in range(1, n + 1)])}\n"
            f"[initial]\nq = {json.dumps(start)}\nv = {json.dumps([0.0] * n)}\n"
        )
    return model + '[method]\nname = "svi"\npoints = 7\nquadrature = 6\n[run]\nh = 0.1\nt_end = 1.0\n'


def lowest_mode(n, t, a=1.0):
    sites = np.arange(1, n + 1)
    omega = 2 * math.sin(math.pi / (2 * (n + 1)))
    return a * np.sin(math.pi * sites / (n + 1)) * math.cos(omega * t)


def test_text_models_and_chains_of_any_size_run_from_python(tmp_path):
    # Twelve coordinates written out by name: one Lagrangian of run-time size, its trajectory
    # in named columns, the binary's digits, the exact solution to round-off.
    n = 12
    named = svi.run(harmonic_chain(n, indexed=False))
    assert named.q.shape == (11, n) and named.model == "text"
    assert np.abs(named.q[-1] - lowest_mode(n, 1.0)).max() < 1e-13
    path = tmp_path / "named.toml"
    path.write_text(harmonic_chain(n, indexed=False))
    assert named.summary["q"] == cli_json("run", str(path), "--json")["q"]
    # The same chain as one indexed sum (local terms): the same state, and the initial state
    # given as n numbers instead of the expression.
    indexed = svi.run(harmonic_chain(n, indexed=True), trajectory=False)
    assert np.abs(np.array(indexed.summary["q"]) - named.q[-1]).max() < 1e-14
    again = svi.run(harmonic_chain(n, indexed=True), initial={"q": named.q[0].tolist(), "v": [0.0] * n}, trajectory=False)
    assert np.abs(np.array(again.summary["q"]) - named.q[-1]).max() < 1e-14
    # Ten thousand sites: the sparse path, the same exact mode.
    big = svi.run(harmonic_chain(n, indexed=True), params={"n": 10_000}, trajectory=False)
    assert len(big.summary["q"]) == 10_000
    assert np.abs(np.array(big.summary["q"]) - lowest_mode(10_000, 1.0)).max() < 1e-13
    # An ensemble of a chain: its rows are the single runs.
    table = svi.ensemble(harmonic_chain(n, indexed=True), params={"a": [0.5, 1.0]}, as_frame=False)
    assert table["status"].tolist() == ["ok", "ok"]
    for row, a in enumerate([0.5, 1.0]):
        single = svi.run(harmonic_chain(n, indexed=True), params={"a": a}, diagnostics=["energy"], trajectory=False)
        assert table["energy_error_max"][row] == single.energy_error_max
        assert table["energy_initial"][row] == pytest.approx(0.25 * a**2 * (n + 1) * (2 * math.sin(math.pi / (2 * (n + 1)))) ** 2, rel=1e-12)
    # A work–precision sweep of a chain, against svi's reference run: Störmer–Verlet's error
    # falls by four when its step halves.
    chain = tmp_path / "chain.toml"
    chain.write_text(harmonic_chain(n, indexed=True))
    records = svi.bench(str(chain), methods="verlet", steps=[10, 20], t_end=1.0, batches=1, min_batch=0, as_frame=False)
    assert records["final_error"][0] / records["final_error"][1] == pytest.approx(4.0, rel=0.02)


def test_every_flag_of_svi_run_is_a_keyword_of_the_calls():
    """Adding a run option is one field of the command line's overrides: its flag is a keyword
    of svi.run, svi.solve and svi.ensemble, parsed by the same parser (same errors)."""
    import re

    _, help_text, _ = cli("run", "--help")
    flags = {flag.replace("-", "_") for flag in re.findall(r"^\s+--([a-z][a-z-]*)", help_text, re.M)}
    not_keywords = {"json", "strict", "help", "param", "out", "plot", "every", "events_out"}
    assert set(svi.options()) == flags - not_keywords, (svi.options(), flags)
    # Each reaches the command line's parser: a value it rejects is bad input naming the flag.
    for name in ["adapt", "recovery", "form", "monitor", "method"]:
        status, _, stderr = cli("run", "kepler", f"--{name.replace('_', '-')}", "bogus")
        assert status == 2
        for call in (
            lambda: svi.run("kepler", **{name: "bogus"}),
            lambda: svi.solve("kepler", 1.0, **{name: "bogus"}),
            lambda: svi.ensemble("kepler", params={"e": [0.5]}, as_frame=False, **{name: "bogus"}),
        ):
            with pytest.raises(svi.InvalidInputError) as caught:
                call()
            assert name.replace("_", "-") in caught.value.message or name in caught.value.message
    # Options outside a call's signature go through its keywords, as the flags do.
    by_keyword = svi.run("kepler", t_end=1.0, trajectory=False, divergence_limit=1e6, max_steps=1000)
    assert by_keyword.summary == svi.run("kepler", t_end=1.0, trajectory=False).summary | {
        "seconds": by_keyword.summary["seconds"]
    }
    with pytest.raises(TypeError, match="frobnicate"):
        svi.run("kepler", frobnicate=1)
