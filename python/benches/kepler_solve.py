"""What the Python front door costs: svi.solve of Kepler (e = 0.5, SVI 7/6, h = 0.02, T = 2000:
10^5 steps, the trajectory of every step returned as NumPy arrays) against the Rust run it
makes — the run's own `seconds` (svi-experiments' Scene::run, in process, the same steps and
the same trajectory kept) — and against `svi run` of the same scene, which keeps no trajectory
(as svi.solve with saveat=[T] does not).

    python python/benches/kepler_solve.py [SVI_BIN]

Prints the medians over 15 alternated repetitions; docs/results/python.md holds a measurement.
"""

import json
import statistics
import subprocess
import sys
import time

import svi

ARGS = dict(method="svi:7/6", h=0.02, diagnostics=["none"])
CLI = ["run", "kepler", "--method", "svi:7/6", "--h", "0.02", "--diagnostics", "none", "--json"]


def main() -> None:
    binary = sys.argv[1] if len(sys.argv) > 1 else None
    rows = {
        "python wall": [],
        "its Rust run": [],
        "saveat=[T] wall": [],
        "dense=True wall": [],
        "svi run (no trajectory)": [],
        "svi run process": [],
    }
    for _ in range(15):
        start = time.perf_counter()
        sol = svi.solve("kepler", 2000.0, **ARGS)
        rows["python wall"].append(time.perf_counter() - start)
        rows["its Rust run"].append(sol.seconds)
        assert sol.steps == 100_000 and sol.q.shape == (100_001, 2)
        start = time.perf_counter()
        svi.solve("kepler", 2000.0, saveat=[2000.0], **ARGS)
        rows["saveat=[T] wall"].append(time.perf_counter() - start)
        start = time.perf_counter()
        svi.solve("kepler", 2000.0, dense=True, **ARGS)
        rows["dense=True wall"].append(time.perf_counter() - start)
        if binary:
            start = time.perf_counter()
            out = subprocess.run([binary, *CLI], capture_output=True, text=True, check=True).stdout
            rows["svi run process"].append(time.perf_counter() - start)
            rows["svi run (no trajectory)"].append(json.loads(out)["seconds"])
    median = {name: statistics.median(values) for name, values in rows.items() if values}
    for name, value in median.items():
        print(f"{name:>26}: {value * 1e3:7.2f} ms")
    print(f"python / its Rust run: {median['python wall'] / median['its Rust run']:.3f}")
    if binary:
        print(f"python / svi run process: {median['python wall'] / median['svi run process']:.3f}")
        print(f"python saveat=[T] / svi run process: {median['saveat=[T] wall'] / median['svi run process']:.3f}")
        print(f"python saveat=[T] / svi run's solve: {median['saveat=[T] wall'] / median['svi run (no trajectory)']:.3f}")


if __name__ == "__main__":
    main()
