"""Holonomic constraints from Python: ``svi.Lagrangian(..., constraints=[...])`` solved by a
constrained method (``method="rattle-kahan-li8"``), the constraint diagnostics and the
multipliers of the Solution, the numbers of ``svi run`` for the built-in constrained scenes,
and bad input as typed errors."""

import json
import math

import numpy as np
import pytest

import svi
from test_svi import cli

#: The spherical pendulum in Cartesian coordinates (unit mass, length l).
SPHERE = dict(q=["x", "y", "z"], params={"g": 9.81, "l": 1.0}, symmetries=[["-y", "x", "0"]])
Q0 = [math.sin(0.8), 0.0, -math.cos(0.8)]


def spherical(constraints=("x^2 + y^2 + z^2 - l^2",), **extra):
    return svi.Lagrangian("0.5*(vx^2 + vy^2 + vz^2) - g*z", constraints=list(constraints), **SPHERE, **extra)


def test_a_constrained_model_stays_on_its_constraints_and_keeps_energy_and_momentum():
    sol = svi.solve(spherical(), (0.0, 10.0), q0=Q0, v0=[0.0, 2.0, 0.0], method="rattle-kahan-li8", h=0.05)
    assert sol.status == "ok" and sol.method == "rattle-kahan-li8" and sol.order == 8
    assert sol.constraint_error_max <= 1e-12 and sol.velocity_constraint_error_max <= 1e-12
    assert sol.constraints == ["x^2 + y^2 + z^2 - l^2"]
    assert sol.energy_error_max <= 1e-8 and sol.momentum_error_max <= 1e-13
    assert sol.q.shape == (201, 3) and sol.t[-1] == 10.0
    # Every point on the sphere, the energy the Legendre transform of L at each.
    assert np.abs(np.sum(sol.q**2, axis=1) - 1.0).max() <= 1e-13
    kinetic = 0.5 * np.sum(sol.v**2, axis=1)
    assert np.abs(sol.energy - (kinetic + 9.81 * sol.q[:, 2])).max() <= 1e-12
    assert sol.multipliers is None


def test_the_multipliers_come_on_request_one_column_per_constraint():
    sol = svi.solve(spherical(), 1.0, q0=Q0, v0=[0.0, 2.0, 0.0], h=0.01, multipliers=True)
    assert sol.method == "rattle"
    assert sol.multipliers.shape == (101, 1)
    assert list(sol.trajectory)[-1] == "lambda_1"
    # The rod's tension holds the point on the sphere: λ > 0 pulls it inwards (the force is −Gᵀλ).
    assert (sol.multipliers[1:, 0] > 0).all()


def test_the_built_in_constrained_scenes_give_the_numbers_of_svi_run():
    for scene in ("spherical-pendulum", "double-pendulum-cartesian", "four-bar-linkage"):
        result = svi.run(scene, t_end=1.0, trajectory=False)
        status, stdout, _ = cli("run", scene, "--t-end", "1", "--json")
        assert status == 0
        expected = json.loads(stdout)
        for field in ("q", "v", "p", "energy_error_max", "constraint_error_max", "velocity_constraint_error_max", "iterations"):
            assert result.summary[field] == expected[field], (scene, field)


def test_a_constraint_violated_at_t0_is_projected_with_a_warning():
    off = [1.001 * x for x in Q0]
    sol = svi.solve(spherical(), 1.0, q0=off, v0=[0.1, 2.0, 0.0], h=0.01)
    assert abs(sol.initial_q_moved - 1e-3) < 1e-9
    assert sol.warnings and sol.warnings[0]["kind"] == "projection"
    assert "projected" in sol.warnings[0]["message"]
    assert np.abs(np.sum(sol.q**2, axis=1) - 1.0).max() <= 1e-13


@pytest.mark.parametrize(
    "constraints, error, needle",
    [
        ([], svi.InvalidParameterError, "the list is empty"),
        (["x^2 + y^2 + z^2 - l^2", "x^2 + y^2 + z^2 - l^2"], svi.InvalidParameterError, "redundant"),
        (["l - 1"], svi.InvalidInputError, "'l - 1'"),
        (["x^2 + y^2 + z^2 - l^2", "x", "y", "z"], svi.InvalidParameterError, "4 constraints on 3 coordinates"),
        (["x*vx"], svi.InvalidInputError, "velocity vx"),
        (["x - t"], svi.InvalidInputError, "time t"),
        (["x^2 + w^2 - 1"], svi.InvalidInputError, "unknown symbol 'w'"),
        (["x^2 +"], svi.InvalidInputError, "syntax error"),
    ],
)
def test_bad_constraints_are_typed_errors_naming_the_constraint(constraints, error, needle):
    with pytest.raises(error) as caught:
        svi.solve(spherical(constraints), 1.0, q0=Q0, v0=[0.0, 2.0, 0.0], h=0.01)
    assert needle in caught.value.message, caught.value.message


def test_a_model_and_its_method_must_agree_about_constraints():
    with pytest.raises(svi.InvalidInputError, match="rattle-kahan-li8"):
        svi.solve(spherical(), 1.0, q0=Q0, v0=[0.0, 2.0, 0.0], h=0.01, method="svi")
    with pytest.raises(svi.InvalidInputError, match="rattle is a constrained method"):
        svi.solve("kepler", 1.0, method="rattle")
    with pytest.raises(svi.InvalidInputError, match="not for a constrained run"):
        svi.solve(spherical(), 1.0, q0=Q0, v0=[0.0, 2.0, 0.0], h=0.01, dense=True)


def test_a_step_newton_cannot_take_is_a_failed_run_with_its_summary():
    with pytest.raises(svi.NonConvergenceError) as caught:
        svi.solve(spherical(), 1000.0, q0=Q0, v0=[0.0, 2.0, 0.0], h=100.0)
    assert caught.value.summary["status"] == "failed"
    assert caught.value.summary["steps"] == 0
    assert caught.value.step == 0
