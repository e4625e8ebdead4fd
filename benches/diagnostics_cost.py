#!/usr/bin/env python3
"""What the default diagnostics cost: every method's run with `--diagnostics none` against
the same run with the default diagnostics (energy and momentum, checked at every step).

For each scene and method the script runs

    svi run SCENE --method METHOD --diagnostics none --json
    svi run SCENE --method METHOD --json

in turn, `--repeat` times each (alternating, so a drift of the machine's speed hits both),
and prints the median of the run's own `seconds` (the stepping loop with its observers,
without process start-up and output) and the ratio of the medians. The issue's target is a
ratio of at most 1.3 for every method on `kepler` and `outer-solar-system`.

Usage:

    python3 benches/diagnostics_cost.py [--svi target/release/svi] [--repeat 5]
        [--scenes kepler,outer-solar-system] [--methods verlet,symplectic-euler,...]
        [--t-end T]

Methods default to every method `svi run --help` lists for these scenes (not the rigid-body
and constrained ones). Requires nothing beyond Python 3.
"""

import argparse
import json
import statistics
import subprocess
import sys

METHODS = ["svi", "svi-newton", "sc", "symplectic-euler", "symplectic-euler-adjoint",
           "midpoint", "verlet", "yoshida4", "kahan-li6", "kahan-li8", "trapezoid",
           "explicit-euler", "implicit-euler", "rk4", "multiscale"]


def seconds(svi, scene, method, diagnostics, t_end):
    """The run's `seconds`, or None if it failed."""
    command = [svi, "run", scene, "--method", method, "--json"]
    if diagnostics is not None:
        command += ["--diagnostics", diagnostics]
    if t_end is not None:
        command += ["--t-end", repr(t_end)]
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0:
        return None
    return json.loads(result.stdout)["seconds"]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--svi", default="target/release/svi")
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--scenes", default="kepler,outer-solar-system")
    parser.add_argument("--methods", default=",".join(METHODS))
    parser.add_argument("--t-end", type=float, help="horizon (default: the scene's)")
    args = parser.parse_args()
    if args.repeat < 1:
        parser.error("--repeat must be at least 1")
    print("scene,method,seconds_none,seconds_default,ratio")
    worst = 0.0
    for scene in args.scenes.split(","):
        for method in args.methods.split(","):
            none, default = [], []
            for _ in range(args.repeat):
                none.append(seconds(args.svi, scene, method, "none", args.t_end))
                default.append(seconds(args.svi, scene, method, None, args.t_end))
            if None in none or None in default:
                print(f"{scene},{method},failed,failed,", flush=True)
                continue
            a, b = statistics.median(none), statistics.median(default)
            worst = max(worst, b / a)
            print(f"{scene},{method},{a:.6f},{b:.6f},{b / a:.3f}", flush=True)
    print(f"largest ratio: {worst:.3f}", file=sys.stderr)


if __name__ == "__main__":
    main()
