#!/usr/bin/env python3
"""svi against heyoka (Taylor's method) and REBOUND's IAS15 on Kepler, alternating in one run.

Each round runs `svi bench kepler` on the listed methods and step counts, then the peers
script `../shared/tools/py-peers/kepler_py_peers.py` (heyoka's tolerances, IAS15's epsilons),
one after the other, so that both see the same machine; the time of each configuration is
the median over the rounds of its in-process time (svi: one timing batch of at least
`--min-batch` seconds per round; the peers: their own median of batches of 0.2 s). The final
errors are the same in every round (deterministic runs) and are taken from the first.

    python3 benches/kepler_taylor.py --ecc 0.5 --t-end 2000 --rounds 5 \\
        --svi svi:11/10=4000,5000,6000 --heyoka 1e-13,1e-14 --ias15 1e-9 \\
        --out kepler-taylor-e0.5.csv --plot kepler-taylor-e0.5.svg

`--svi METHOD=STEPS,...` is repeatable (any method of `svi bench --methods`, run at these
`--steps`, or at these `--tolerances` for dop853, dopri5, radau5 and METHOD@step); the peers run with the interpreter `--python` (heyoka, rebound and numpy
installed: see the peers' README). CSV on stdout or `--out`: `code,method,parameter,steps,
final_error,energy_error,seconds,rounds`, where `parameter` is svi's step count or tolerance, heyoka's
`tol` or IAS15's `epsilon`, `energy_error` is svi's largest over the run and the peers' at T,
and `seconds` the median in-process time. `--plot` draws error against time (matplotlib).
"""
import argparse
import csv
import io
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PEERS = ROOT.parent / "shared" / "tools" / "py-peers" / "kepler_py_peers.py"


def adaptive(method):
    """Whether `svi bench` runs `method` at tolerances (the adaptive peers, step doubling)."""
    return method in ("dop853", "dopri5", "radau5") or method.endswith("@step")


def svi_round(binary, ecc, t_end, specs, min_batch):
    """One `svi bench` call per method: {(method, parameter): (error, energy error, seconds,
    steps)}."""
    rows = {}
    with tempfile.TemporaryDirectory() as out:
        for method, values in specs:
            command = [
                binary, "bench", "kepler", "--param", f"e={ecc}", "--t-end", str(t_end),
                "--methods", method, "--tolerances" if adaptive(method) else "--steps", values,
                "--batches", "1", "--min-batch", str(min_batch), "--out-dir", out,
            ]
            subprocess.run(command, check=True, stdout=subprocess.DEVNULL)
            with open(os.path.join(out, "kepler.csv")) as f:
                for row in csv.DictReader(f):
                    rows[(row["method"], float(row["parameter"]))] = (
                        float(row["final_error"]),
                        float(row["energy_error_max"]),
                        float(row["seconds"]),
                        int(row["steps"]),
                    )
    return rows


def peers_round(python, ecc, t_end, heyoka, ias15):
    """One call of the peers script: {(code, parameter): (error, energy error, seconds, steps)}."""
    command = [
        python, str(PEERS), "--ecc", str(ecc), "--t-end", str(t_end),
        "--heyoka", heyoka, "--ias15", ias15, "--rounds", "1",
    ]
    text = subprocess.run(command, check=True, capture_output=True, text=True).stdout
    return {
        (row["method"], row["parameter"]): (
            float(row["final_error"]),
            float(row["max_energy_error"]),
            float(row["median_seconds"]),
            row["steps"],
        )
        for row in csv.DictReader(io.StringIO(text))
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--svi-binary", default=os.environ.get(
        "SVI_BIN", str(ROOT / "target" / "release" / "svi")))
    parser.add_argument("--python", default=sys.executable,
                        help="interpreter with heyoka, rebound and numpy")
    parser.add_argument("--ecc", type=float, default=0.5)
    parser.add_argument("--t-end", type=float, default=2000.0)
    parser.add_argument("--svi", action="append", default=[], metavar="METHOD=STEPS,...")
    parser.add_argument("--heyoka", default="1e-13,1e-14")
    parser.add_argument("--ias15", default="1e-9")
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--min-batch", type=float, default=0.2)
    parser.add_argument("--out")
    parser.add_argument("--plot")
    args = parser.parse_args()
    if args.rounds < 1:
        parser.error("--rounds must be at least 1")
    specs = []
    for spec in args.svi:
        method, sep, steps = spec.partition("=")
        if not sep or not steps:
            parser.error(f"--svi {spec!r}: expected METHOD=STEPS,STEPS,...")
        specs.append((method, steps))

    svi_times, peer_times = {}, {}
    svi_first, peer_first = None, None
    for r in range(args.rounds):
        print(f"round {r + 1} of {args.rounds}", file=sys.stderr, flush=True)
        rows = svi_round(args.svi_binary, args.ecc, args.t_end, specs, args.min_batch)
        svi_first = svi_first or rows
        for key, value in rows.items():
            svi_times.setdefault(key, []).append(value[2])
        if args.heyoka or args.ias15:
            rows = peers_round(args.python, args.ecc, args.t_end, args.heyoka, args.ias15)
            peer_first = peer_first or rows
            for key, value in rows.items():
                peer_times.setdefault(key, []).append(value[2])

    table = []
    for (method, parameter), (error, energy, _, steps) in sorted((svi_first or {}).items()):
        times = svi_times[(method, parameter)]
        code = {"dop853": "ode_solvers", "dopri5": "ode_solvers",
                "radau5": "differential-equations"}.get(method, "svi")
        table.append((code, method, f"{parameter:g}", steps, error, energy,
                      statistics.median(times), len(times)))
    for (code, parameter), (error, energy, _, steps) in (peer_first or {}).items():
        times = peer_times[(code, parameter)]
        table.append((code, code, parameter, steps, error, energy, statistics.median(times),
                      len(times)))

    out = open(args.out, "w", newline="") if args.out else sys.stdout
    writer = csv.writer(out)
    writer.writerow(["code", "method", "parameter", "steps", "final_error", "energy_error",
                     "seconds", "rounds"])
    for row in table:
        writer.writerow(row[:4] + tuple(f"{x:.4e}" for x in row[4:7]) + row[7:])
    if args.out:
        out.close()

    if args.plot:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        figure, axes = plt.subplots(figsize=(8, 5))
        for method in dict.fromkeys(row[1] for row in table):
            points = sorted((row[6], row[4]) for row in table if row[1] == method)
            axes.loglog([p[0] * 1e3 for p in points], [p[1] for p in points], "o-",
                        label=method, markersize=4)
        axes.set_xlabel("in-process run time [ms]")
        axes.set_ylabel(f"final position error at T = {args.t_end:g}")
        axes.set_title(f"Kepler e = {args.ecc:g}, T = {args.t_end:g}: in-process time, "
                       f"median of {args.rounds} alternating rounds")
        axes.grid(True, which="both", alpha=0.3)
        axes.legend(fontsize=8)
        figure.tight_layout()
        figure.savefig(args.plot)


if __name__ == "__main__":
    main()
