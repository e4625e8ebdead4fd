#!/usr/bin/env python3
"""Compare svi's MEGNO map with REBOUND's on the same (a, e) grid: the share of cells both call
chaotic (MEGNO > 4) or both regular.

    svi ensemble restricted-three-body --param a=0.5:0.95:20 --param e=0:0.5:20 \\
        --indicators megno --t-end 1256.6370614359173 --out svi.csv
    python3 benches/megno_map_rebound.py --a 0.5:0.95:20 --e 0:0.5:20 \\
        --t-end 1256.6370614359173 --out rebound.csv
    python3 benches/megno_map_compare.py svi.csv rebound.csv

A member svi could not run to the end (a step's Newton iteration failing at a close encounter
with Jupiter) and an orbit REBOUND lost (MEGNO inf or negative: an escape) count as chaotic.
Standard library only.
"""

import csv
import math
import sys


def chaotic(value):
    return not math.isfinite(value) or value < 0 or value > 4


def main(svi_path, rebound_path):
    rebound = {}
    with open(rebound_path, newline="") as f:
        for row in csv.DictReader(f):
            rebound[(round(float(row["a"]), 9), round(float(row["e"]), 9))] = float(row["megno"])
    agree = total = 0
    with open(svi_path, newline="") as f:
        for row in csv.DictReader(f):
            key = (round(float(row["a"]), 9), round(float(row["e"]), 9))
            if key not in rebound:
                sys.exit(f"cell a = {key[0]}, e = {key[1]} is not in {rebound_path}")
            mine = float(row["megno"]) if row["status"] == "ok" else math.inf
            total += 1
            agree += chaotic(mine) == chaotic(rebound[key])
    if total != len(rebound):
        sys.exit(f"{svi_path} has {total} cells, {rebound_path} {len(rebound)}")
    print(f"{agree} of {total} cells agree ({agree / total:.1%})")


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
