"""The gradient of a loss from Python (``svi.gradient``, the discrete adjoint): against the
forward sensitivities of the same run (``sensitivity=``, to 1e-10) and against central
differences of whole runs (to 1e-7), for Kepler (e, q0) and the damped pendulum (l, c, θ0), on
SVI, the midpoint rule and Störmer–Verlet; and typed errors for a bad loss, name or budget."""

import math

import numpy as np
import pytest

import svi


def loss(j, t, q, v):
    """ℓ_j = (1 + j/10) q₁ + ½|q̇|²: a weight per output, both q and q̇ in it."""
    weight = 1.0 + 0.1 * j
    dq = np.zeros_like(q)
    dq[0] = weight
    return weight * q[0] + 0.5 * v @ v, dq, v


def loss_of(outputs):
    """J of the outputs of a run's sensitivity block (their q and v)."""
    return sum(loss(j, o["t"], np.array(o["q"]), np.array(o["v"]))[0] for j, o in enumerate(outputs))


def by_sensitivities(scene, wrt, **run):
    """J and ∇J by the chain rule through the forward sensitivities of every output."""
    result = svi.run(scene, trajectory=False, diagnostics=["none"], sensitivity=wrt, **run)
    outputs = result.summary["sensitivity"]["outputs"]
    total = np.zeros(len(result.summary["sensitivity"]["columns"]))
    for j, o in enumerate(outputs):
        q, v = np.array(o["q"]), np.array(o["v"])
        _, dq, dv = loss(j, o["t"], q, v)
        total += np.concatenate([dq, dv]) @ np.array(o["jacobian"])
    return loss_of(outputs), total


def loss_at(scene, wrt, **run):
    """J of one run (its outputs taken from the sensitivity block)."""
    result = svi.run(scene, trajectory=False, diagnostics=["none"], sensitivity=wrt, **run)
    return loss_of(result.summary["sensitivity"]["outputs"])


CASES = [
    # Kepler's e moves the start (the model's own initial state); its q0 with a given start.
    ("kepler", "svi:7/6", ["e"], dict(h=0.05, t_end=5.0, sensitivity_every=10, params={"e": 0.5})),
    ("kepler", "verlet", ["e"], dict(h=0.01, t_end=3.0, sensitivity_every=50, params={"e": 0.5})),
    ("kepler", "midpoint", ["q0", "v0"],
     dict(h=0.02, t_end=3.0, sensitivity_every=25, initial={"q": [0.5, 0.0], "v": [0.0, 1.7]})),
    # The damped pendulum's l and c enter L and the force: the run is lifted.
    ("damped-pendulum", "svi:5", ["l", "c", "q0"],
     dict(h=0.1, t_end=4.0, sensitivity_every=8, params={"l": 1.3, "c": 0.2},
          initial={"q": [1.0], "v": [0.0]})),
    ("damped-pendulum", "midpoint", ["c", "l"],
     dict(h=0.02, t_end=2.0, sensitivity_every=20, params={"l": 1.3, "c": 0.2})),
]


@pytest.mark.parametrize("scene,method,wrt,run", CASES)
def test_the_adjoint_gradient_is_the_sensitivities_chain_rule(scene, method, wrt, run):
    value, reference = by_sensitivities(scene, wrt, method=method, **run)
    run = dict(run)
    every = run.pop("sensitivity_every")
    result = svi.gradient(scene, loss, wrt, method, every=every, checkpoints=3, **run)
    assert result.value == pytest.approx(value, rel=1e-12)
    difference = np.abs(result.gradient - reference).max() / np.abs(reference).max()
    print(f"{scene} {method} {wrt}: {difference:.1e} from the sensitivities' chain rule")
    assert difference <= 1e-10
    # The default checkpoints (⌈√K⌉) give the same numbers.
    again = svi.gradient(scene, loss, wrt, method, every=every, **run)
    assert np.abs(again.gradient - result.gradient).max() <= 1e-12 * np.abs(reference).max()


def test_the_gradient_matches_central_differences_of_whole_runs():
    params = {"l": 1.3, "c": 0.2}
    start = {"q": [1.0], "v": [0.0]}
    run = dict(method="svi:5", h=0.1, t_end=4.0)
    result = svi.gradient("damped-pendulum", loss, "l,c,q0", every=8, params=params, initial=start, **run)
    assert result.columns == ["l", "c", "q0_theta"]
    for name, delta in [("l", 1e-5), ("c", 1e-5), ("q0_theta", 1e-6)]:
        def shifted(sign):
            moved_params, moved_start = dict(params), {k: list(x) for k, x in start.items()}
            if name == "q0_theta":
                moved_start["q"][0] += sign * delta
            else:
                moved_params[name] += sign * delta
            return loss_at("damped-pendulum", ["c"], params=moved_params, initial=moved_start,
                           sensitivity_every=8, **run)

        difference = (shifted(1.0) - shifted(-1.0)) / (2 * delta)
        print(f"{name}: {abs(result[name] / difference - 1):.1e} from central differences")
        assert result[name] == pytest.approx(difference, rel=1e-7), name


def test_bad_losses_names_and_budgets_are_typed_errors():
    run = dict(h=0.05, t_end=1.0)
    with pytest.raises(svi.InvalidParameterError, match="'mass'"):
        svi.gradient("kepler", loss, ["mass"], **run)
    with pytest.raises(svi.SviError, match="kepler, damped-pendulum"):
        svi.gradient("pendulum", loss, ["q0"], **run)
    with pytest.raises(svi.InvalidInputError, match="wrt"):
        svi.gradient("kepler", loss, [], **run)
    with pytest.raises(svi.InvalidInputError, match="wrt"):
        svi.gradient("kepler", loss, "e,,q0", **run)
    with pytest.raises(svi.ArgumentTypeError, match="wrt"):
        svi.gradient("kepler", loss, [3], **run)
    with pytest.raises(svi.InvalidParameterError, match="checkpoints"):
        svi.gradient("kepler", loss, ["e"], checkpoints=0, **run)

    def nan(j, t, q, v):
        return (math.nan if j == 1 else 0.0), np.zeros_like(q), np.zeros_like(v)

    with pytest.raises(svi.NonFiniteError, match="loss at output 1"):
        svi.gradient("kepler", nan, ["e"], every=5, **run)

    def short(j, t, q, v):
        return 0.0, [1.0], v

    with pytest.raises(svi.ArgumentTypeError, match=r"gradient at output \d+ has 1 and 2 entries"):
        svi.gradient("kepler", short, ["e"], **run)

    class Raised(Exception):
        pass

    def raising(j, t, q, v):
        raise Raised("the user's own")

    with pytest.raises(Raised, match="the user's own"):
        svi.gradient("kepler", raising, ["e"], **run)
    with pytest.raises(svi.ArgumentTypeError, match="loss"):
        svi.gradient("kepler", lambda j, t, q, v: None, ["e"], **run)
    with pytest.raises(svi.ArgumentTypeError, match="loss"):
        svi.gradient("kepler", 3.0, ["e"], **run)
