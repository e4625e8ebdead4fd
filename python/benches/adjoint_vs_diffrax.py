"""The gradient of a loss of a Kepler run by svi's discrete adjoint (svi.gradient) against
JAX/diffrax's (Dopri8 and Tsit5 with RecursiveCheckpointAdjoint, float64), at equal gradient
accuracy (issue #40: time ratio, target ≤ 0.5×).

Kepler e = 0.5 from its pericentre, T = 20 (about three orbits), J = Σ_j q₁(t_j) over
t_j = 0, 1, …, 20; the gradient with respect to the initial state (q₀, q̇₀). Its reference is
diffrax's Dopri8 at rtol = atol = 1e-14, checked against svi 9/8 at h = 1/200. Each solver runs
over a ladder of steps (svi) or tolerances (diffrax); a run's error is the largest entry of its
gradient's difference from the reference, relative to the largest entry of the reference.
Times are medians of repeated calls after a first (for diffrax: the jit-compiled function,
compile time excluded; for svi: the whole Python call, scene set-up included).

    pip install jax diffrax     # not part of the package's requirements
    python python/benches/adjoint_vs_diffrax.py

Prints every run, then for each error target the cheapest run of each solver and the ratio.
"""

import statistics
import time

import jax
import jax.numpy as jnp
import numpy as np

import svi

jax.config.update("jax_enable_x64", True)
import diffrax  # noqa: E402  (after x64 is enabled)

E = 0.5
Q0 = np.array([1.0 - E, 0.0])
V0 = np.array([0.0, np.sqrt((1.0 + E) / (1.0 - E))])
T = 20.0
TIMES = np.arange(0.0, T + 0.5, 1.0)
TARGETS = [1e-6, 1e-8, 1e-10]


def median_time(call, repeats):
    call()
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def diffrax_gradient(solver, rtol, atol, max_steps=200_000):
    """A jitted function of (q0, v0) giving ∇J, by diffrax with RecursiveCheckpointAdjoint."""

    def field(t, y, args):
        q, v = y[:2], y[2:]
        r3 = jnp.sum(q * q) ** 1.5
        return jnp.concatenate([v, -q / r3])

    def loss(y0):
        solution = diffrax.diffeqsolve(
            diffrax.ODETerm(field), solver, t0=0.0, t1=T, dt0=1e-3, y0=y0,
            saveat=diffrax.SaveAt(ts=jnp.asarray(TIMES)),
            stepsize_controller=diffrax.PIDController(rtol=rtol, atol=atol),
            adjoint=diffrax.RecursiveCheckpointAdjoint(), max_steps=max_steps,
        )
        return jnp.sum(solution.ys[:, 0])

    gradient = jax.jit(jax.grad(loss))
    y0 = jnp.concatenate([jnp.asarray(Q0), jnp.asarray(V0)])
    return lambda: np.asarray(gradient(y0).block_until_ready())


def svi_gradient(method, per_unit):
    """∇J by svi's discrete adjoint: h = 1/per_unit, an output every per_unit steps."""

    def loss(j, t, q, v):
        dq = np.zeros_like(q)
        dq[0] = 1.0
        return q[0], dq, np.zeros_like(v)

    def call():
        result = svi.gradient("kepler", loss, ["q0", "v0"], method, h=1.0 / per_unit, t_end=T,
                              every=per_unit, initial={"q": Q0, "v": V0})
        return result.gradient

    return call


def main():
    reference = diffrax_gradient(diffrax.Dopri8(), 1e-14, 1e-14)()
    check = svi_gradient("svi:9/8", 200)()
    scale = np.abs(reference).max()
    print(f"reference ∇J = {reference}; svi 9/8 at h = 1/200 differs by "
          f"{np.abs(check - reference).max() / scale:.1e}")
    runs = []
    for method in ["svi:7/6", "svi:9/8"]:
        for per_unit in [4, 5, 7, 10, 14, 20, 40, 80]:
            call = svi_gradient(method, per_unit)
            error = np.abs(call() - reference).max() / scale
            seconds = median_time(call, 7)
            runs.append(("svi", f"{method} h=1/{per_unit}", error, seconds))
    for name, solver in [("Dopri8", diffrax.Dopri8()), ("Tsit5", diffrax.Tsit5())]:
        for tol in [1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12]:
            call = diffrax_gradient(solver, tol, tol)
            error = np.abs(call() - reference).max() / scale
            seconds = median_time(call, 7)
            runs.append(("diffrax", f"{name} tol={tol:.0e}", error, seconds))
    for kind, label, error, seconds in runs:
        print(f"{kind:8s} {label:22s} error {error:8.1e}  {seconds * 1e3:9.3f} ms")
    print()
    for target in TARGETS:
        best = {}
        for kind, label, error, seconds in runs:
            if error <= target and (kind not in best or seconds < best[kind][1]):
                best[kind] = (label, seconds)
        if len(best) == 2:
            (a, ta), (b, tb) = best["svi"], best["diffrax"]
            print(f"error ≤ {target:.0e}: svi {a} {ta * 1e3:.3f} ms, diffrax {b} {tb * 1e3:.3f} ms, "
                  f"ratio {ta / tb:.3f}")
        else:
            print(f"error ≤ {target:.0e}: reached by {sorted(best) or 'neither'} only")


if __name__ == "__main__":
    main()
