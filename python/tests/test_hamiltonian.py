"""svi.Hamiltonian and the Octave package's call svi.solve(odefun, tspan, y0).

References: the Lagrange–d'Alembert run of the same damped pendulum (svi.Lagrangian with a
friction force, SVI with the same points and steps, whose map svi-h reproduces through the
Legendre map); Kepler's exact circular orbit; the same model written as L."""

import math

import numpy as np
import pytest

import svi

#: Friction of the damped pendulum (m = l = g = 1).
C = 0.1


def damped(t, y):
    """Hamilton's equations of the damped pendulum, θ' = p, p' = −sin θ − c p."""
    return [y[1], -math.sin(y[0]) - C * y[1]]


def test_the_octave_call_reproduces_the_lagrange_dalembert_run():
    """spectralvarint(odefun, tspan, y0) on the damped pendulum (f_H = −c p) against the
    Lagrange–d'Alembert run of L = θ̇²/2 + cos θ with f_L = −c θ̇: 1e-10 at the listed times."""
    times = [0.0, 1.0, 2.5, 5.0, 10.0, 20.0]
    octave = svi.solve(damped, times, [1.0, 0.0], adapt="none", h=0.1)
    pendulum = svi.Lagrangian("0.5*vth^2 + cos(th)", q=["th"], forces=["-c*vth"], params={"c": C})
    lagrange = svi.solve(pendulum, (0.0, 20.0), q0=[1.0], v0=[0.0], h=0.1, saveat=times, diagnostics=["none"])
    assert octave.method == "svi-h:6/12"
    np.testing.assert_array_equal(octave.t, times)
    assert octave.y.shape == (len(times), 2)
    # The Lagrangian run's trajectory starts at t0 and holds the output times after it.
    rows = [list(lagrange.t).index(t) for t in times]
    difference = np.abs(octave.y - np.hstack([lagrange.q[rows], lagrange.p[rows]])).max()
    assert difference < 1e-10, difference
    # With the Jacobian given: the same solution.
    exact = svi.solve(damped, times, [1.0, 0.0], adapt="none", h=0.1, jac=lambda t, y: [[0.0, 1.0], [-math.cos(y[0]), -C]])
    assert np.abs(exact.y - octave.y).max() < 1e-12


def test_the_octave_call_with_its_defaults():
    """tspan = (t0, t_end): every accepted step of step doubling to tol = 1e-8; the final state
    against a fine fixed-step run."""
    sol = svi.solve(damped, (0.0, 10.0), [2.0, 0.5])
    assert sol.t[0] == 0.0 and sol.t[-1] == pytest.approx(10.0, abs=1e-12)
    assert len(sol.t) == sol.accepted_steps + 1 and np.all(np.diff(sol.t) > 0)
    assert sol.steps > sol.accepted_steps  # the trial steps of step doubling
    reference = svi.solve(damped, [0.0, 10.0], [2.0, 0.5], adapt="none", h=0.01)
    assert np.abs(sol.y[-1] - reference.y[-1]).max() < 1e-7
    # Other methods on Hamilton's equations.
    for method, tolerance in (("sc-h", 1e-7), ("midpoint-h", 1e-4)):
        other = svi.solve(damped, (0.0, 10.0), [2.0, 0.5], method=method, adapt="none", h=0.01)
        assert np.abs(other.y[-1] - reference.y[-1]).max() < tolerance, method


def test_odefun_bad_input_is_a_typed_error():
    with pytest.raises(svi.InvalidInputError):
        svi.solve(damped, (0.0, 1.0), [1.0, 0.0, 2.0])  # odd length
    with pytest.raises(svi.InvalidInputError):
        svi.solve(damped, 1.0, [1.0, 0.0])  # no t0
    with pytest.raises(svi.InvalidInputError):
        svi.solve(damped, (0.0, 1.0), [1.0, 0.0], diagnostics=["energy"])  # no H, no energy
    # A method on the Euler–Lagrange equations: the model has no Lagrangian.
    with pytest.raises(svi.InvalidParameterError, match="no Lagrangian"):
        svi.solve(damped, (0.0, 1.0), [1.0, 0.0], method="svi")
    # odefun's own exception is raised again, and a result of the wrong shape is a TypeError.
    def broken(t, y):
        raise ZeroDivisionError("inside odefun")

    with pytest.raises(ZeroDivisionError, match="inside odefun"):
        svi.solve(broken, (0.0, 1.0), [1.0, 0.0])
    with pytest.raises(svi.ArgumentTypeError, match=r"odefun\(t, y\).*shape \(2,\)"):
        svi.solve(lambda t, y: [0.0, 0.0, 0.0], (0.0, 1.0), [1.0, 0.0])
    with pytest.raises(svi.ArgumentTypeError, match="jac"):
        svi.solve(damped, (0.0, 1.0), [1.0, 0.0], jac=lambda t, y: [1.0, 2.0])
    # Non-finite at the initial state.
    with pytest.raises(svi.NonFiniteError):
        svi.solve(lambda t, y: [math.nan, 0.0], (0.0, 1.0), [1.0, 0.0])


def test_a_hamiltonian_written_as_text_runs_on_every_kind_of_method():
    """Kepler's circular orbit written as H: svi-h, sc-h, verlet-h and (through the Legendre
    map) svi reach the exact orbit; the same run as the Lagrangian agrees with svi-h."""
    kepler = svi.Hamiltonian("0.5*(px^2 + py^2) - mu/sqrt(x^2 + y^2)", q=["x", "y"], params={"mu": 1.0})
    assert "Hamiltonian(" in repr(kepler)
    t_end = 2 * math.pi
    for method, h, tolerance in (("svi-h", 0.1, 1e-10), ("sc-h:8", 0.05, 1e-9), ("verlet-h", 0.001, 1e-4), ("svi", 0.1, 1e-10)):
        sol = svi.solve(kepler, (0.0, t_end), q0=[1.0, 0.0], p0=[0.0, 1.0], method=method, h=h)
        assert sol.status == "ok"
        error = np.abs(sol.q[-1] - [math.cos(t_end), math.sin(t_end)]).max()
        assert error < tolerance, (method, error)
        assert sol.energy_error_max < max(tolerance, 1e-12) * 10, (method, sol.energy_error_max)
    lagrangian = svi.Lagrangian("0.5*(vx^2 + vy^2) + mu/sqrt(x^2 + y^2)", q=["x", "y"], params={"mu": 1.0})
    a = svi.solve(kepler, (0.0, 3.0), y0=[1.0, 0.0, 0.0, 1.1], method="svi-h", h=0.1)
    b = svi.solve(lagrangian, (0.0, 3.0), q0=[1.0, 0.0], p0=[0.0, 1.1], method="svi", h=0.1)
    assert np.abs(a.q - b.q).max() < 1e-12
    # f_H: friction −c p makes the energy decay.
    damped_text = svi.Hamiltonian("0.5*pth^2 - cos(th)", q=["th"], forces=["-c*pth"], params={"c": C})
    sol = svi.solve(damped_text, (0.0, 20.0), q0=[1.0], p0=[0.0], method="svi-h", h=0.1)
    octave = svi.solve(damped, [0.0, 20.0], [1.0, 0.0], adapt="none", h=0.1)
    assert np.abs(sol.y[-1] - octave.y[-1]).max() < 1e-10


def test_a_text_hamiltonian_with_an_unknown_symbol_is_a_typed_error():
    with pytest.raises(svi.InvalidInputError, match="vx"):
        svi.solve(svi.Hamiltonian("0.5*vx^2 + x^2", q=["x"]), (0.0, 1.0), q0=[1.0], p0=[0.0])


def test_the_energy_of_a_general_text_hamiltonian_is_h():
    """A relativistic (separable, not quadratic) text H on an explicit composition: the energy
    diagnostic is H itself, finite and conserved to the method's accuracy (it solved a Legendre
    map for L and came out NaN before)."""
    pair = svi.Hamiltonian("sqrt(1 + px^2) + sqrt(1 + py^2) + 0.5*(x^2 + y^2) - 0.1*x*y", q=["x", "y"])
    sol = svi.solve(pair, (0.0, 100.0), q0=[1.0, 0.0], p0=[0.0, 2.0], method="kahan-li8-h", h=0.05)
    assert sol.status == "ok" and sol.iterations == 0
    assert sol.energy_error_max is not None and sol.energy_error_max < 1e-9, sol.energy_error_max
    energy = np.sqrt(1 + sol.p[:, 0] ** 2) + np.sqrt(1 + sol.p[:, 1] ** 2) + 0.5 * (sol.q**2).sum(axis=1) - 0.1 * sol.q[:, 0] * sol.q[:, 1]
    assert np.abs(sol.energy - energy).max() < 1e-12


def test_hostile_odefun_calls_raise_svi_errors_or_odefuns_own():
    """The Octave call with hostile right-hand sides, spans, states and options: a solution
    whose numbers are finite (or warned about), an SviError, or the exception odefun raised."""
    import random

    rng = random.Random(20261205)
    hostile = [None, True, 0, -1, 2, 0.5, -0.3, 1e-300, 1e300, math.inf, math.nan, "1", "", [], [1.0], (0.0, 1.0), {}, object()]

    def raising(t, y):
        raise ZeroDivisionError("odefun's own")

    odefuns = [damped, lambda t, y: [math.nan, 0.0], lambda t, y: "ab", lambda t, y: [[y[1]], [-y[0]]], lambda t, y: None, raising, lambda t, y: [y[1] * 1e300, 1e300]]
    outcomes = {"result": 0, "error": 0}
    for _ in range(120):
        keywords = {name: rng.choice(hostile) for name in rng.sample(["method", "h", "tol", "adapt", "max_steps", "jac"], rng.randint(0, 2))}
        keywords.setdefault("max_steps", 20_000)
        # The well-formed choice half of the time each, so that some calls run.
        span = (0.0, 1.0) if rng.random() < 0.5 else rng.choice([[0.0, 0.5, 1.0], (1.0, 0.0), 1.0, (0.0, math.inf), "x", [0.0]])
        y0 = [1.0, 0.0] if rng.random() < 0.5 else rng.choice([[1.0], [math.nan, 0.0], "ab", [1.0, 0.0, 0.0, 0.0], None])
        odefun = damped if rng.random() < 0.5 else rng.choice(odefuns)
        try:
            sol = svi.solve(odefun, span, y0, **keywords)
        except svi.SviError as error:
            assert error.message and "panicked" not in error.message
            outcomes["error"] += 1
            continue
        except ZeroDivisionError as error:
            assert str(error) == "odefun's own"
            outcomes["error"] += 1
            continue
        assert sol.status == "ok" and (np.isfinite(sol.y).all() or sol.summary.get("warnings")), sol.summary
        outcomes["result"] += 1
    assert outcomes["result"] > 0 and outcomes["error"] > 0, outcomes
