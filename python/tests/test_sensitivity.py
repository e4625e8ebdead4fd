"""Derivatives of a run from Python (``sensitivity=``): the Jacobians of ``svi run
--sensitivity`` against central differences of whole runs, and typed errors for what cannot be
differentiated."""

import numpy as np
import pytest

import svi

RUN = dict(h=0.05, t_end=4.0, trajectory=False, diagnostics=["none"])


def final(params=None, q0=1.0):
    result = svi.run("damped-pendulum", params=params or {}, initial={"q": [q0], "v": [0.0]}, **RUN)
    return np.array(result.summary["q"] + result.summary["v"])


def test_the_pendulum_jacobian_matches_central_differences():
    result = svi.run("damped-pendulum", params={"l": 1.3, "c": 0.2}, initial={"q": [1.0], "v": [0.0]},
                     sensitivity=["l", "c", "q0"], sensitivity_every=20, **RUN)
    block = result.summary["sensitivity"]
    assert block["columns"] == ["l", "c", "q0_theta"]
    assert block["rows"] == ["q_theta", "v_theta"]
    assert [o["t"] for o in block["outputs"]] == pytest.approx([0.0, 1.0, 2.0, 3.0, 4.0])
    jacobian = np.array(block["outputs"][-1]["jacobian"])
    delta = 1e-5
    columns = [
        (final({"l": 1.3 + delta, "c": 0.2}) - final({"l": 1.3 - delta, "c": 0.2})),
        (final({"l": 1.3, "c": 0.2 + delta}) - final({"l": 1.3, "c": 0.2 - delta})),
        (final({"l": 1.3, "c": 0.2}, 1.0 + delta) - final({"l": 1.3, "c": 0.2}, 1.0 - delta)),
    ]
    differences = np.array(columns).T / (2 * delta)
    assert np.abs(jacobian - differences).max() <= 1e-7 * np.abs(differences).max()


def test_what_cannot_be_differentiated_is_a_typed_error():
    with pytest.raises(svi.InvalidParameterError, match="'mass'"):
        svi.run("kepler", t_end=1.0, sensitivity=["mass"])
    with pytest.raises(svi.SviError, match="kepler, damped-pendulum"):
        svi.run("pendulum", t_end=1.0, sensitivity=["q0"])
    with pytest.raises(svi.SviError, match="0 steps"):
        svi.run("kepler", t_end=1.0, sensitivity=["e"], sensitivity_every=0)
