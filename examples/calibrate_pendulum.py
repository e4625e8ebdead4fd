# Fit the damped pendulum's length l, friction c and initial angle θ0 to 200 noisy samples of
# its angle with scipy.optimize.least_squares, driven by svi's exact derivatives of the run
# (--sensitivity): the residuals' Jacobian is ∂θ(t_j)/∂(l, c, θ0) of the discrete map itself.
import functools
import matplotlib.pyplot as plt, numpy as np, svi
from scipy.optimize import least_squares

truth = {"l": 1.3, "c": 0.15, "theta0": 1.1}
h, every, samples, sigma = 0.01, 10, 200, 0.01   # 200 samples, every 0.1 over [0.1, 20]
t_end = h * every * samples


def angle_and_jacobian(x):
    """θ at the samples and ∂θ/∂(l, c, θ0) there, by one run of SVI on the damped pendulum."""
    l, c, theta0 = x
    result = svi.run("damped-pendulum", "svi:5", h=h, t_end=t_end, params={"l": l, "c": c},
                     initial={"q": [theta0], "v": [0.0]}, trajectory=False, diagnostics=["none"],
                     sensitivity=["l", "c", "q0"], sensitivity_every=every)
    outputs = result.summary["sensitivity"]["outputs"][1:]   # the samples, without the start
    theta = np.array([o["q"][0] for o in outputs])
    jacobian = np.array([o["jacobian"][0] for o in outputs])  # row q_theta: columns l, c, q0
    return theta, jacobian


rng = np.random.default_rng(20261206)
exact, _ = angle_and_jacobian([truth["l"], truth["c"], truth["theta0"]])
data = exact + sigma * rng.standard_normal(samples)
t = h * every * np.arange(1, samples + 1)

@functools.lru_cache(maxsize=1)   # least_squares asks for the residuals, then the Jacobian
def run_at(x):
    return angle_and_jacobian(x)

def run(x):
    return run_at(tuple(x))

fit = least_squares(lambda x: run(x)[0] - data, x0=[1.0, 0.1, 1.0], jac=lambda x: run(x)[1],
                    x_scale="jac", xtol=1e-12, ftol=1e-12)
# The statistical error: the covariance σ² (JᵀJ)⁻¹ of the estimate.
covariance = sigma ** 2 * np.linalg.inv(fit.jac.T @ fit.jac)
errors = np.sqrt(np.diag(covariance))
print(f"{fit.nfev} runs; residual rms {np.sqrt(np.mean(fit.fun ** 2)):.4f} (noise σ = {sigma})")
for name, value, error in zip(truth, fit.x, errors):
    off = (value - truth[name]) / error
    print(f"  {name:7s} = {value:.5f} ± {error:.5f}   truth {truth[name]:.5f}   off by {off:+.2f} σ")
    assert abs(off) < 4.0, f"{name}: recovered {value}, truth {truth[name]} ({off:.1f} σ)"

fig, ax = plt.subplots()
ax.plot(t, data, ".", ms=3, label="samples")
ax.plot(t, run(fit.x)[0], label="fit")
ax.set_xlabel("t"), ax.set_ylabel("θ"), ax.legend()
fig.savefig("calibrate-pendulum.png")
