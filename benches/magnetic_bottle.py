#!/usr/bin/env python3
"""A long run of the magnetic bottle with a Hamiltonian method: energy, p_φ and the
adiabatic magnetic moment μ, with their drift (issue #39).

Runs `svi run magnetic-bottle --method METHOD --t-end T --every K --out CSV --json`, then
reads the trajectory: the energy column, and μ = m v_⊥²/(2|B|) with
B = B₀(−xz/L², −yz/L², 1 + z²/L²) recomputed from (x, v). μ oscillates within each
gyration and each bounce (it is an adiabatic invariant, conserved to O(ε)), so its drift is
measured on the means over whole bounces (z crossing 0 upwards), fitted by a straight line.

    python3 benches/magnetic_bottle.py --svi target/release/svi --method svi-h:4/3 --steps 1000000
"""

import argparse
import json
import math
import subprocess
import sys
import tempfile
from pathlib import Path


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--svi", default="target/release/svi", help="the svi binary")
    parser.add_argument("--method", default="svi-h:4/3")
    parser.add_argument("--steps", type=int, default=1_000_000, help="steps of the default h")
    parser.add_argument("--every", type=int, default=25, help="write every K-th step")
    args = parser.parse_args()

    h = 2 * math.pi / 32  # the model's default step (32 steps per gyration at the centre)
    t_end = args.steps * h
    with tempfile.TemporaryDirectory() as directory:
        csv = Path(directory) / "bottle.csv"
        result = subprocess.run(
            [args.svi, "run", "magnetic-bottle", "--method", args.method, "--t-end", repr(t_end),
             "--every", str(args.every), "--out", str(csv), "--json"],
            capture_output=True, text=True, check=True)
        summary = json.loads(result.stdout)
        rows = csv.read_text().splitlines()
    parameters = summary["parameters"]
    m, b0, length = parameters["m"], parameters["b0"], parameters["l"]
    header = rows[0].split(",")
    column = {name: i for i, name in enumerate(header)}
    times, energies, moments, heights = [], [], [], []
    for line in rows[1:]:
        values = [float(x) for x in line.split(",")]
        x, y, z = (values[column[f"q_{c}"]] for c in "xyz")
        v = [values[column[f"v_{c}"]] for c in "xyz"]
        field = [-b0 * x * z / length**2, -b0 * y * z / length**2, b0 * (1 + z * z / length**2)]
        size = math.sqrt(sum(b * b for b in field))
        along = sum(a * b for a, b in zip(v, field)) / size
        across = sum(a * a for a in v) - along * along
        times.append(values[column["t"]])
        energies.append(values[column["energy"]])
        moments.append(m * across / (2 * size))
        heights.append(z)

    energy0, moment0 = energies[0], moments[0]
    count = len(energies)
    tenth = max(count // 10, 1)
    first = max(abs(e - energy0) for e in energies[:tenth])
    last = max(abs(e - energy0) for e in energies[-tenth:])
    # Means of μ over whole bounces: from one upward zero crossing of z to the next.
    crossings = [i for i in range(1, count) if heights[i - 1] < 0 <= heights[i]]
    means, centres = [], []
    for a, b in zip(crossings, crossings[1:]):
        means.append(sum(moments[a:b]) / (b - a))
        centres.append(0.5 * (times[a] + times[b]))
    n = len(means)
    slope = 0.0
    if n >= 2:
        tm, mm = sum(centres) / n, sum(means) / n
        slope = sum((t - tm) * (u - mm) for t, u in zip(centres, means)) / sum(
            (t - tm) ** 2 for t in centres)
    print(f"{args.method}: {summary['steps']} steps in {summary['seconds']:.2f} s "
          f"({1e6 * summary['seconds'] / summary['steps']:.2f} µs/step), T = {t_end:.1f}")
    print(f"energy: max |E − E0| = {summary['energy_error_max']:.2e} "
          f"({summary['energy_error_max'] / abs(energy0):.1e} of E0); on the trajectory's first "
          f"tenth {first:.2e}, last tenth {last:.2e}")
    print(f"p_phi (Noether): max error {summary['momentum_error_max']:.2e}")
    band = max(abs(u - moment0) for u in moments) / moment0
    spread = (max(means) - min(means)) / moment0 if means else float("nan")
    print(f"mu: within {band:.3%} of mu0 at every written step; {n} bounce means spread "
          f"{spread:.1e} of mu0; fitted drift over the run {slope * (times[-1] - times[0]) / moment0:.1e} "
          f"of mu0")
    print(f"trapped: max |z| = {max(abs(z) for z in heights):.3f} (L = {length})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
