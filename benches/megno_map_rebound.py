#!/usr/bin/env python3
"""MEGNO map of the planar circular restricted three-body problem by REBOUND.

The reference for svi's chaos indicators on the model `restricted-three-body`
(models/src/restricted_three_body.rs): the same initial conditions, integrated by REBOUND
in its inertial frame, with REBOUND's MEGNO (Cincotta & Simo 2000; REBOUND: Rein & Tamayo
2015, "WHFast", MNRAS 452, 376, which introduced its variational equations and MEGNO).

Requirements (this script installs nothing):

    pip install rebound numpy

System, in the units of the svi model (G = 1, the primaries' distance and total mass 1, their
period 2 pi):
- the Sun, mass 1 - mu, and Jupiter, mass mu, on a circular orbit of radius 1 about each
  other (mu defaults to svi's 1/(1 + 1047.348644), the IAU 2009 mass ratio);
- a test particle (mass 0) on the heliocentric two-body orbit of semi-major axis a and
  eccentricity e about the Sun alone (G M = 1 - mu), prograde, with its pericentre on the
  line from the Sun through Jupiter and the particle at that pericentre at t = 0 (velocity
  perpendicular to that line);
- then the centre of mass is moved to rest at the origin (sim.move_to_com()).
At t = 0 the inertial frame coincides with svi's rotating frame, so the Jacobi constant
C = 2 Omega - |v - omega x r|^2, Omega = (x^2 + y^2)/2 + (1 - mu)/r1 + mu/r2, computed from
REBOUND's particle equals svi's `jacobi` invariant (`--check-jacobi` prints both).

For every (a, e) of the grid the script integrates to t_end with REBOUND's MEGNO
(sim.init_megno()) and writes one CSV row `a,e,megno,seconds` (seconds: the wall time of that
point), in grid order as the orbits finish; a particle that goes further than 5 from the
centre of mass gets megno = inf. The total wall time goes to standard error.
MEGNO tends to 2 on a regular (quasi-periodic) orbit and grows like lambda t / 2 on a chaotic
one (lambda the maximal Lyapunov exponent): > 4 is chaotic, as read in MEGNO maps.

The integrator is WHFast (symplectic, fixed step, the one REBOUND's MEGNO tutorial uses for
stability maps, "Stability map with MEGNO and WHFast") with a step of 1/`--steps-per-orbit` of
the shorter of the particle's and Jupiter's periods, integrated to the nearest step
(exact_finish_time = 0, so that the step stays constant). WHFast's fixed step does not resolve
close encounters with Jupiter, and an orbit it loses that way (a spurious escape: at a = 0.7,
e = 0.3, WHFast ejects the particle at t = 342 where IAS15 keeps it, MEGNO 29) is redone with
IAS15, REBOUND's adaptive 15th-order integrator; `--integrator ias15` uses IAS15 for every
orbit (about 10 times slower, for checking).

Usage:

    python3 benches/megno_map_rebound.py                       # 20 x 20 grid, T = 2 pi 200
    python3 benches/megno_map_rebound.py --a 0.4:0.95:56 --e 0:0.5:26 --t-end 6283.2 \\
        --threads 2 --out megno.csv
    python3 benches/megno_map_rebound.py --check-jacobi 0.6,0.1 --svi target/release/svi

Options: --a LO:HI:N and --e LO:HI:N (inclusive grids, N points each), --t-end T, --threads K
(worker processes), --mu MU, --integrator whfast|ias15, --steps-per-orbit S, --encounter R
(end an orbit closer than R to the Sun or Jupiter, counted as lost: MEGNO inf), --out FILE
(default: standard output), --check-jacobi A,E [--svi PATH].
"""

import argparse
import json
import math
import multiprocessing
import subprocess
import sys
import time

import numpy as np
import rebound

SUN_JUPITER = 1.0 / (1.0 + 1047.348644)
ESCAPE_RADIUS = 5.0


def grid(text):
    """Parse LO:HI:N into N equally spaced values from LO to HI inclusive."""
    try:
        lo, hi, n = text.split(":")
        lo, hi, n = float(lo), float(hi), int(n)
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{text}' is not LO:HI:N")
    if n < 1 or not (math.isfinite(lo) and math.isfinite(hi)):
        raise argparse.ArgumentTypeError(f"'{text}': N must be at least 1, LO and HI finite")
    return np.linspace(lo, hi, n) if n > 1 else np.array([lo])


def simulation(mu, a, e, integrator, steps_per_orbit, encounter=0.0):
    """The Sun, Jupiter and the test particle at t = 0, centre of mass at rest."""
    sim = rebound.Simulation()
    sim.G = 1.0
    sim.add(m=1.0 - mu)
    # Jupiter: circular orbit of radius 1 about the Sun, on the +x axis (true anomaly 0).
    sim.add(m=mu, a=1.0, e=0.0, f=0.0)
    # The particle: heliocentric elements about the Sun alone (G M = 1 - mu for m = 0), at
    # its pericentre (omega = 0, f = 0) on the +x axis, prograde.
    sim.add(m=0.0, a=a, e=e, omega=0.0, f=0.0, primary=sim.particles[0])
    sim.move_to_com()
    sim.integrator = integrator
    if integrator == "whfast":
        period = 2.0 * math.pi * min(1.0, a ** 1.5 / math.sqrt(1.0 - mu))
        sim.dt = period / steps_per_orbit
    sim.exit_max_distance = ESCAPE_RADIUS
    if encounter > 0.0:
        sim.exit_min_distance = encounter
    return sim


def jacobi(mu, particle):
    """C = 2 Omega - |v - omega x r|^2 at t = 0 (the frames coincide)."""
    x, y = particle.x, particle.y
    r1 = math.hypot(x + mu, y)
    r2 = math.hypot(x - 1.0 + mu, y)
    omega = 0.5 * (x * x + y * y) + (1.0 - mu) / r1 + mu / r2
    vx, vy = particle.vx + y, particle.vy - x
    return 2.0 * omega - (vx * vx + vy * vy)


def run_megno(mu, a, e, t_end, integrator, steps_per_orbit, encounter):
    """MEGNO at t_end, or None if the particle escapes, comes closer than `encounter` to a
    primary (when positive) or the run stops early."""
    sim = simulation(mu, a, e, integrator, steps_per_orbit, encounter)
    sim.init_megno(seed=0)
    try:
        sim.integrate(t_end, exact_finish_time=0)
    except (rebound.Escape, rebound.Encounter, rebound.Collision):
        return None
    value = sim.megno()
    return value if math.isfinite(value) else None


def megno(job):
    """MEGNO of one grid point; returns (a, e, megno, seconds)."""
    a, e, mu, t_end, integrator, steps_per_orbit, encounter = job
    start = time.perf_counter()
    value = run_megno(mu, a, e, t_end, integrator, steps_per_orbit, encounter)
    if value is None and integrator == "whfast":
        # WHFast's fixed step does not resolve close encounters with Jupiter: an orbit it
        # loses is redone with IAS15.
        value = run_megno(mu, a, e, t_end, "ias15", steps_per_orbit, encounter)
    return a, e, math.inf if value is None else value, time.perf_counter() - start


def check_jacobi(mu, a, e, svi):
    """Print the Jacobi constant of (a, e) from REBOUND's particle and, with `svi`, svi's."""
    sim = simulation(mu, a, e, "whfast", 100)
    particle = sim.particles[2]
    print(f"a = {a}, e = {e}, mu = {mu!r}")
    print(f"  REBOUND initial state x = {particle.x!r}, y = {particle.y!r}, "
          f"vx = {particle.vx!r}, vy = {particle.vy!r} (inertial)")
    print(f"  REBOUND Jacobi constant C = {jacobi(mu, particle)!r}")
    if svi:
        command = [svi, "run", "restricted-three-body", "--param", f"mu={mu!r}",
                   "--param", f"a={a!r}", "--param", f"e={e!r}", "--t-end", "0.1",
                   "--h", "0.05", "--json"]
        result = json.loads(subprocess.run(command, check=True, capture_output=True,
                                           text=True).stdout)
        print(f"  svi     Jacobi constant C = {-2.0 * result['energy_initial']!r} "
              f"(-2 x energy_initial of `{' '.join(command)}`)")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--a", type=grid, default="0.5:0.95:20", metavar="LO:HI:N",
                        help="semi-major axes (default 0.5:0.95:20)")
    parser.add_argument("--e", type=grid, default="0:0.5:20", metavar="LO:HI:N",
                        help="eccentricities (default 0:0.5:20)")
    parser.add_argument("--t-end", type=float, default=2.0 * math.pi * 200.0,
                        help="horizon (default 2 pi 200: 200 periods of Jupiter)")
    parser.add_argument("--threads", type=int, default=multiprocessing.cpu_count(),
                        help="worker processes (default: the number of CPUs)")
    parser.add_argument("--mu", type=float, default=SUN_JUPITER,
                        help="mass ratio (default Sun-Jupiter 1/(1 + 1047.348644))")
    parser.add_argument("--integrator", choices=["whfast", "ias15"], default="whfast")
    parser.add_argument("--steps-per-orbit", type=float, default=60.0,
                        help="WHFast steps per period of the particle or Jupiter, whichever "
                             "is shorter (default 60)")
    parser.add_argument("--encounter", type=float, default=0.0, metavar="R",
                        help="end an orbit that comes closer than R to a primary, MEGNO inf "
                             "(default 0: never; IAS15 may then grind through a near-collision "
                             "with Jupiter for a very long time)")
    parser.add_argument("--out", help="CSV file (default: standard output)")
    parser.add_argument("--check-jacobi", metavar="A,E",
                        help="print the Jacobi constant of one (a, e) and exit")
    parser.add_argument("--svi", help="with --check-jacobi: the svi binary, to compare")
    args = parser.parse_args()
    if not 0.0 < args.mu <= 0.5:
        parser.error("--mu must be in (0, 1/2]")
    if args.check_jacobi:
        a, e = (float(x) for x in args.check_jacobi.split(","))
        check_jacobi(args.mu, a, e, args.svi)
        return
    if args.t_end <= 0.0 or args.threads < 1 or args.steps_per_orbit <= 0.0:
        parser.error("--t-end, --threads and --steps-per-orbit must be positive")
    if np.any(args.a <= 0.0) or np.any(args.e < 0.0) or np.any(args.e >= 1.0):
        parser.error("a must be positive and 0 <= e < 1")

    jobs = [(float(a), float(e), args.mu, args.t_end, args.integrator, args.steps_per_orbit,
             args.encounter) for a in args.a for e in args.e]
    out = open(args.out, "w") if args.out else sys.stdout
    out.write("a,e,megno,seconds\n")
    rows = []
    start = time.perf_counter()
    # Rows are written as the orbits finish (in grid order), so a long map shows its progress
    # and an interrupted one keeps what it computed.
    with multiprocessing.Pool(args.threads) as pool:
        for a, e, value, seconds in pool.imap(megno, jobs, chunksize=4):
            rows.append((a, e, value, seconds))
            out.write(f"{a!r},{e!r},{value!r},{seconds:.6f}\n")
            out.flush()
    total = time.perf_counter() - start
    if args.out:
        out.close()
    finite = [row[2] for row in rows if math.isfinite(row[2])]
    print(f"{len(rows)} orbits ({len(args.a)} a x {len(args.e)} e), t_end = {args.t_end:g}, "
          f"{args.integrator}, {args.threads} processes: {total:.2f} s wall "
          f"({sum(row[3] for row in rows):.2f} s in simulations); MEGNO <= 2.5: "
          f"{sum(v <= 2.5 for v in finite)}, > 4: {sum(v > 4 for v in finite)}, "
          f"escaped: {len(rows) - len(finite)}", file=sys.stderr)


if __name__ == "__main__":
    main()
