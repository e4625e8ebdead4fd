# The Octave package's call, [T, Y] = spectralvarint(odefun, tspan, y0): the damped pendulum
# as the right-hand side of Hamilton's equations, y = (θ, p), f_H = −c p.
import math

import matplotlib.pyplot as plt, numpy as np, svi

c = 0.1

def odefun(t, y):
    return [y[1], -math.sin(y[0]) - c * y[1]]

sol = svi.solve(odefun, np.linspace(0.0, 30.0, 301), [2.5, 0.0])  # svi-h, step doubling, tol 1e-8
T, Y = sol.t, sol.y
# The same system written as L with the friction force f_L = −c θ̇ (Lagrange–d'Alembert).
pendulum = svi.Lagrangian("0.5*vth^2 + cos(th)", q=["th"], forces=["-c*vth"], params={"c": c})
lagrange = svi.solve(pendulum, T, q0=[2.5], v0=[0.0], adapt="step", tol=1e-8, diagnostics=["none"])
print(f"{sol.accepted_steps} steps; largest difference from the Lagrangian run: {np.abs(Y[:, 0] - lagrange.q[:, 0]).max():.1e}")
fig, (angle, energy) = plt.subplots(2, 1, sharex=True)
angle.plot(T, Y[:, 0]), angle.set_ylabel("θ")
energy.plot(T, 0.5 * Y[:, 1] ** 2 - np.cos(Y[:, 0])), energy.set_ylabel("energy, dE/dt = −c p²")
energy.set_xlabel("t")
fig.savefig("damped-pendulum.png")
