"""svi.Lagrangian, svi.solve and svi.Solution: models written in Python, solutions evaluated
at any time by the method's own step polynomials."""

import math
import os

import numpy as np
import pytest

import svi

DOUBLE_PENDULUM = svi.Lagrangian(
    "0.5*(m1 + m2)*l1^2*vth1^2 + 0.5*m2*l2^2*vth2^2 + m2*l1*l2*vth1*vth2*cos(th1 - th2)"
    " + (m1 + m2)*g*l1*cos(th1) + m2*g*l2*cos(th2)",
    q=["th1", "th2"],
    params={"m1": 1.0, "m2": 1.0, "l1": 1.0, "l2": 1.0, "g": 9.81},
)


def test_the_readme_double_pendulum_conserves_energy_and_evaluates_anywhere(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    sol = svi.solve(DOUBLE_PENDULUM, (0.0, 10.0), q0=[1.0, 0.5], v0=[0.0, 0.0], method="svi:7/6", h=0.01, dense=True)
    assert sol.status == "ok" and sol.steps == 1000
    assert sol.t.shape == (1001,) and sol.q.shape == (1001, 2)
    # Symplectic: the energy error stays at the method's accuracy over the run.
    energy_error = np.abs(sol.energy - sol.energy[0])
    assert energy_error.max() == pytest.approx(sol.energy_error_max, rel=1e-12)
    assert sol.energy_error_max < 1e-9
    times = np.linspace(0.0, 10.0, 1000)
    q = sol(times)
    assert q.shape == (1000, 2)
    # At the steps' ends, sol(t) is the state the run reports.
    assert np.abs(sol(sol.t[::50]) - sol.q[::50]).max() < 1e-12
    # The package wrote no file.
    assert os.listdir(tmp_path) == []


def test_sol_t_is_the_methods_dense_output():
    """sol(t) against the states a second solve serves at those times (read off the same step
    polynomials during the run): equal to 1e-14 relative to 1 + |x|, for SVI, SC and with step
    doubling; to 1e-13 for a method without a polynomial (midpoint: the cubic Hermite
    interpolant, whose q̇ carries 1e-16/h of rounding)."""
    times = np.sort(np.random.default_rng(7).uniform(0.0, 5.0, 1000))
    # The Hermite interpolant's q̇ divides differences of q by h: its own rounding, 1e-16/h.
    for method, options, tol in [
        ("svi:7/6", {"h": 0.05}, 1e-14),
        ("sc:8", {"h": 0.05}, 1e-14),
        ("midpoint", {"h": 0.01}, 1e-13),
        ("svi:6", {"adapt": "step", "tol": 1e-9}, 1e-14),
    ]:
        kept = svi.solve(DOUBLE_PENDULUM, (0.0, 5.0), q0=[1.0, 0.5], v0=[0.0, 0.0], method=method, dense=True, **options)
        served = svi.solve(
            DOUBLE_PENDULUM, (0.0, 5.0), q0=[1.0, 0.5], v0=[0.0, 0.0], method=method, saveat=times, **options
        )
        assert served.t[1:] == pytest.approx(times, abs=0)
        for what, column in (("q", served.q), ("v", served.v)):
            # Relative to the number's size (1 + |x|): rounding in the barycentric sums.
            difference = (np.abs(kept(times, what) - column[1:]) / (1.0 + np.abs(column[1:]))).max()
            assert difference < tol, (method, what, difference)


def test_sol_t_converges_to_the_exact_oscillator_at_the_methods_order():
    """q = cos t: the error of sol(t) at 2000 times between steps falls as h^7 or faster for SVI
    with 7 points (the step polynomial's degree 6, its nodes superconvergent)."""
    oscillator = svi.Lagrangian("0.5*vx^2 - 0.5*x^2", q=["x"])
    times = np.linspace(0.0, 8.0, 2000)
    errors = []
    for h in (0.4, 0.2):
        sol = svi.solve(oscillator, 8.0, q0=[1.0], v0=[0.0], method="svi:7/6", h=h, dense=True)
        errors.append(np.abs(sol(times)[:, 0] - np.cos(times)).max())
    assert errors[1] < 1e-8
    assert math.log2(errors[0] / errors[1]) > 6.0, errors


def test_a_zoo_model_solves_with_its_defaults_and_the_exact_kepler_orbit_is_met():
    sol = svi.solve("kepler", 20.0, method="svi:9/8", h=0.05, diagnostics=["solution"], dense=True)
    assert sol.solution_error_max < 1e-9
    # The step polynomials in between are as accurate as the steps.
    assert np.abs(sol(sol.t) - sol.q).max() < 1e-12


def test_scalars_arrays_and_bad_times():
    sol = svi.solve(DOUBLE_PENDULUM, 1.0, q0=[1.0, 0.5], v0=[0.0, 0.0], h=0.1, dense=True)
    assert sol(0.5).shape == (2,)
    assert sol(np.zeros((3, 4))).shape == (3, 4, 2)
    assert sol.span == (0.0, 1.0)
    for bad in (-0.1, 1.5, float("nan")):
        with pytest.raises(svi.InvalidParameterError, match="time"):
            sol(bad)
    with pytest.raises(ValueError):
        sol(0.5, "x")
    without = svi.solve(DOUBLE_PENDULUM, 1.0, q0=[1.0, 0.5], v0=[0.0, 0.0], h=0.1)
    with pytest.raises(AttributeError, match="dense=True"):
        without(0.5)


def test_a_model_with_a_mistake_is_a_typed_error_naming_it():
    bad = svi.Lagrangian("0.5*vx^2 - k*x^2", q=["x"])
    with pytest.raises(svi.InvalidInputError, match="unknown symbol 'k'"):
        svi.solve(bad, 1.0, q0=[1.0], v0=[0.0], h=0.1)
    with pytest.raises(svi.ArgumentTypeError):
        svi.Lagrangian(3j, q=["x"])
    with pytest.raises(TypeError, match="bogus"):
        svi.solve(DOUBLE_PENDULUM, 1.0, q0=[1.0, 0.5], v0=[0.0, 0.0], h=0.1, bogus=1)


def test_forces_and_symmetries():
    """A damped oscillator's energy decays as the exact solution's; the free particle's
    momentum, the Noether momentum of translations, is conserved."""
    damped = svi.Lagrangian("0.5*vx^2 - 0.5*x^2", q=["x"], params={"c": 0.1}, forces=["-c*vx"])
    sol = svi.solve(damped, 10.0, q0=[1.0], v0=[0.0], method="svi:8/8", h=0.05)
    gamma = 0.05
    omega = math.sqrt(1.0 - gamma**2)
    exact = math.exp(-gamma * 10.0) * (math.cos(omega * 10.0) + gamma / omega * math.sin(omega * 10.0))
    assert sol.q[-1, 0] == pytest.approx(exact, abs=1e-10)
    planar = svi.Lagrangian("0.5*(vx^2 + vy^2) - 0.5*y^2", q=["x", "y"], symmetries=[["1", "0"]])
    sol = svi.solve(planar, 10.0, q0=[0.0, 1.0], v0=[0.3, 0.0], h=0.1)
    assert sol.momentum_error_max < 1e-13


def test_sympy_expressions():
    sympy = pytest.importorskip("sympy")
    th, vth = sympy.symbols("th vth")
    pendulum = svi.Lagrangian(sympy.Rational(1, 2) * vth**2 + sympy.cos(th) * sympy.E, q=[th])
    assert pendulum.expr == "vth^2/2 + e*cos(th)"
    sol = svi.solve(pendulum, 1.0, q0=[0.1], v0=[0.0], h=0.1)
    assert sol.status == "ok"


def test_the_readme_python_example_is_the_example_file_ci_runs():
    """The README shows examples/double_pendulum.py as it is (CI runs the file)."""
    root = os.path.join(os.path.dirname(__file__), "..", "..")
    with open(os.path.join(root, "README.md"), encoding="utf-8") as readme:
        text = readme.read()
    with open(os.path.join(root, "examples", "double_pendulum.py"), encoding="utf-8") as example:
        script = example.read()
    assert "```python\n" + script + "```" in text


def test_a_chain_written_in_python_is_the_scene_written_as_text():
    """An indexed chain (q[1..n], sums) from svi.Lagrangian gives the numbers of the same chain
    as a scene's text, digit for digit: one model, two front doors."""
    expr = "sum(i, 1, n, 0.5*vq[i]^2) - sum(i, 1, n - 1, 0.5*(q[i+1] - q[i])^2 + 0.25*(q[i+1] - q[i])^4)"
    q0 = [math.sin(k) for k in range(8)]
    chain = svi.Lagrangian(expr, q=["q[1..n]"], params={"n": 8})
    sol = svi.solve(chain, 10.0, q0=q0, v0=[0.0] * 8, h=0.05, method="verlet", dense=True)
    scene = f"""
lagrangian = "{expr}"
coordinates = ["q[1..n]"]
[parameters]
n = 8
[initial]
q = {q0!r}
v = {[0.0] * 8!r}
[method]
name = "verlet"
[run]
h = 0.05
t_end = 10.0
"""
    run = svi.run(scene)
    assert sol.summary["q"] == run.summary["q"] and sol.steps == run.steps == 200
    assert sol.energy_error_max == run.energy_error_max < 1e-2
    assert np.abs(sol(10.0) - np.array(run.summary["q"])).max() < 1e-13


def test_an_ensemble_over_a_model_object_is_its_members_solves():
    """svi.ensemble over a Lagrangian (its parameter varied, from one base state): each
    member's row has the numbers of svi.solve of that member."""
    oscillator = svi.Lagrangian("0.5*vx^2 - 0.5*w^2*x^2", q=["x"], params={"w": 1.0})
    table = svi.ensemble(
        oscillator, params={"w": [0.5, 1.0, 2.0]}, q0=[1.0], v0=[0.0], h=0.1, t_end=5.0, method="svi:6", as_frame=False
    )
    assert list(table["status"]) == ["ok"] * 3
    for w, energy_error in zip(table["w"], table["energy_error_max"]):
        sol = svi.solve(oscillator, 5.0, q0=[1.0], v0=[0.0], h=0.1, method="svi:6", params={"w": w})
        assert energy_error == sol.energy_error_max
    with pytest.raises(svi.InvalidInputError, match="initial"):
        svi.ensemble(oscillator, params={"w": [0.5, 1.0]}, h=0.1, t_end=5.0)


@pytest.mark.parametrize(
    "model, kwargs",
    [
        (DOUBLE_PENDULUM, dict(q0=[1.0], v0=[0.0, 0.0], h=0.1)),  # too few components
        (DOUBLE_PENDULUM, dict(q0=[float("nan"), 0.0], v0=[0.0, 0.0], h=0.1)),
        (DOUBLE_PENDULUM, dict(q0=[1.0, 0.0], v0=[0.0, 0.0], h=0.0)),
        (DOUBLE_PENDULUM, dict(q0=[1.0, 0.0], v0=[0.0, 0.0], h=float("inf"))),
        (DOUBLE_PENDULUM, dict(q0=[1.0, 0.0], v0=[0.0, 0.0], p0=[0.0, 0.0], h=0.1)),  # v and p
        (DOUBLE_PENDULUM, dict(q0=[1.0, 0.0], v0=[0.0, 0.0], h=0.1, saveat=[2.0, 1.0])),
        (DOUBLE_PENDULUM, dict(q0=[1.0, 0.0], v0=[0.0, 0.0], h=0.1, adapt="reparam", dense=True)),
        (svi.Lagrangian("", q=["x"]), dict(q0=[1.0], v0=[0.0], h=0.1)),
        (svi.Lagrangian("0.5*vx^2", q=[]), dict(q0=[], v0=[], h=0.1)),
        (svi.Lagrangian("0.5*vx^2 +", q=["x"]), dict(q0=[1.0], v0=[0.0], h=0.1)),
    ],
)
def test_hostile_solves_are_typed_bad_input(model, kwargs):
    """Bad models and arguments of svi.solve: an SviError marked bad input, never a crash."""
    with pytest.raises(svi.SviError) as error:
        svi.solve(model, 1.0, **kwargs)
    assert error.value.bad_input, error.value
