"""Models on Lie groups other than SO(3) from Python: the same summaries and trajectories as
`svi run NAME --json`, initial states on the group (``log`` or ``g``, ``xi`` or ``momentum``),
and typed errors for bad ones."""

import json
import math
import subprocess

import numpy as np
import pytest

import svi
from svi_binary import svi_binary


def test_the_falling_body_runs_as_on_the_command_line():
    result = svi.run("falling-body", t_end=2.0)
    done = subprocess.run(
        [svi_binary(), "run", "falling-body", "--t-end", "2", "--json"], capture_output=True, text=True, check=True
    )
    reference = json.loads(done.stdout)
    assert result.summary["kind"] == "lie_group"
    assert result.summary["g"] == reference["g"]
    assert result.summary["momentum_names"] == ["L_z", "p_x", "p_y"]
    assert result.summary["solution_error_final"] < 1e-8
    assert result.summary["group_defect_max"] < 1e-14
    # The trajectory: the configuration's 12 entries, ξ, μ, the energy and the group defect.
    columns = list(result.trajectory)
    assert columns[:2] == ["t", "g_1"] and columns[-2:] == ["energy", "defect"]
    assert len(columns) == 1 + 12 + 6 + 6 + 2
    assert len(result.t) == 201
    assert np.all(result.trajectory["defect"] < 1e-14)
    assert np.ptp(result.energy) < 1e-8 * abs(result.energy[0])


def test_an_initial_state_on_the_group():
    # At rest at the origin, thrown straight up at 5 m/s: x₃(1) = 5 − g₀/2 exactly.
    result = svi.run("falling-body", t_end=1.0, initial={"log": [0.0] * 6, "xi": [0, 0, 0, 0, 0, 5.0]})
    assert math.isclose(result.summary["g"][11], 5.0 - 0.5 * 9.81, abs_tol=1e-12)
    # The satellite's rotor momentum p = J(Ω₃ + φ̇) is a body momentum given as such.
    momentum = [0.0, 2.0, 0.0, 1.0]
    result = svi.run("dual-spin", t_end=1.0, initial={"momentum": momentum})
    assert result.summary["momentum"][3] == pytest.approx(1.0, abs=1e-14)
    assert result.summary["momentum_error_relative"] < 1e-14


def test_bad_initial_states_on_a_group_are_typed_errors():
    with pytest.raises(svi.InvalidParameterError) as caught:
        svi.run("falling-body", initial={"log": [0.1, 0.2]})
    assert "initial.log: 2 components; need 6" in caught.value.message
    with pytest.raises(svi.InvalidParameterError) as caught:
        svi.run("falling-body", initial={"g": [1, 0, 0, 0, 1, 0, 0, 0, 1.1, 0, 0, 0]})
    assert "not in SE(3)" in caught.value.message
    with pytest.raises(svi.SviError) as caught:
        svi.run("dual-spin", initial={"q": [1.0]})
    assert "lives on a Lie group" in caught.value.message
