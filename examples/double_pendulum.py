import matplotlib.pyplot as plt, numpy as np, svi

pendulum = svi.Lagrangian(  # two unit masses on rods of unit length, in their two angles
    "vth1^2 + 0.5*vth2^2 + vth1*vth2*cos(th1 - th2) + 2*g*cos(th1) + g*cos(th2)",
    q=["th1", "th2"], params={"g": 9.81})
sol = svi.solve(pendulum, (0.0, 20.0), q0=[1.5, 0.0], v0=[0.0, 0.0], method="svi:7/6", h=0.01, dense=True)
t = np.linspace(0.0, 20.0, 1000)
fig, (angles, energy) = plt.subplots(2, 1, sharex=True)
angles.plot(t, sol(t)), angles.set_ylabel("angles")                     # sol(t): any time
energy.semilogy(sol.t, abs(sol.energy - sol.energy[0]) + 1e-16), energy.set_ylabel("energy error")
fig.savefig("double-pendulum.png")
