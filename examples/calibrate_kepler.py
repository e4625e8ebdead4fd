# Fit a Kepler orbit's eccentricity e and phase (the mean anomaly of the start) to 50 noisy
# positions with scipy.optimize.least_squares, driven by svi's exact derivatives of the run
# (--sensitivity e,phase): the residuals' Jacobian is ∂q(t_j)/∂(e, phase) of the discrete map.
import functools
import matplotlib.pyplot as plt, numpy as np, svi
from scipy.optimize import least_squares

truth = {"e": 0.6, "phase": 0.8}
h, every, samples, sigma = 0.02, 15, 50, 0.005   # 50 positions, every 0.3 over [0.3, 15]
t_end = h * every * samples


def positions_and_jacobian(x):
    """q at the samples (50 × 2) and ∂q/∂(e, phase) there (100 × 2), by one run of SVI."""
    e, phase = x
    result = svi.run("kepler", "svi:7/6", h=h, t_end=t_end, params={"e": e, "phase": phase},
                     trajectory=False, diagnostics=["none"], sensitivity=["e", "phase"],
                     sensitivity_every=every)
    outputs = result.summary["sensitivity"]["outputs"][1:]   # the samples, without the start
    q = np.array([o["q"] for o in outputs])
    jacobian = np.array([o["jacobian"][:2] for o in outputs])   # rows q_q1, q_q2
    return q.ravel(), jacobian.reshape(-1, 2)


rng = np.random.default_rng(20261206)
exact, _ = positions_and_jacobian([truth["e"], truth["phase"]])
data = exact + sigma * rng.standard_normal(exact.shape)

@functools.lru_cache(maxsize=1)   # least_squares asks for the residuals, then the Jacobian
def run_at(x):
    return positions_and_jacobian(x)

def run(x):
    return run_at(tuple(x))

# A start far from the truth: a rounder orbit, a third of a radian behind.
fit = least_squares(lambda x: run(x)[0] - data, x0=[0.3, 0.5], jac=lambda x: run(x)[1],
                    bounds=([0.0, -np.inf], [0.95, np.inf]), x_scale="jac",
                    xtol=1e-12, ftol=1e-12)
# The statistical error: the covariance σ² (JᵀJ)⁻¹ of the estimate.
covariance = sigma ** 2 * np.linalg.inv(fit.jac.T @ fit.jac)
errors = np.sqrt(np.diag(covariance))
print(f"{fit.nfev} runs; residual rms {np.sqrt(np.mean(fit.fun ** 2)):.4f} (noise σ = {sigma})")
for name, value, error in zip(truth, fit.x, errors):
    off = (value - truth[name]) / error
    print(f"  {name:6s} = {value:.5f} ± {error:.5f}   truth {truth[name]:.5f}   off by {off:+.2f} σ")
    assert abs(off) < 4.0, f"{name}: recovered {value}, truth {truth[name]} ({off:.1f} σ)"

fitted = run(fit.x)[0].reshape(-1, 2)
noisy = data.reshape(-1, 2)
fig, ax = plt.subplots()
ax.plot(noisy[:, 0], noisy[:, 1], ".", ms=4, label="positions")
ax.plot(fitted[:, 0], fitted[:, 1], "-", lw=1, label="fit")
ax.plot([0], [0], "k+", label="focus")
ax.set_aspect("equal"), ax.set_xlabel("q1"), ax.set_ylabel("q2"), ax.legend()
fig.savefig("calibrate-kepler.png")
