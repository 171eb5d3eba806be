#!/usr/bin/env python3
"""Two builds' default fit side by side: `bench/fit 1 --default-only` from
build A and from build B in interleaved rounds (A B, then B A, ...), so
that a shared machine's load falls on both alike; prints each round's
wall seconds (the fit's own `wall` line), the medians and the median of
the per-round ratios B / A.  A change to the fitter is judged by this
ratio and by bench/fit_instructions.py's count, not by a lone time.
Both builds read the same cached reference photo (bench-out/, made by
the first run where it is missing).

usage: bench/fit_ab.py BUILD_A BUILD_B [ROUNDS]   (default 9 rounds)"""
import os
import re
import statistics
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "bench"))
from page import bench_args  # noqa: E402
WALL = re.compile(r"^  wall\s+([\d.]+)$", re.M)


def wall(build):
    exe = os.path.join(build, "bench", "fit")
    p = subprocess.run([exe, "1", "--default-only"], capture_output=True,
                       text=True, cwd=ROOT)
    m = WALL.search(p.stdout)
    if p.returncode != 0 or not m:
        sys.exit(f"{exe}: exit {p.returncode}, no wall time:\n{p.stderr[-2000:]}")
    return float(m.group(1))


def main():
    args = sys.argv[1:]
    usage = bench_args(__doc__, args)
    if len(args) not in (2, 3) or not all(
            os.path.isfile(os.path.join(b, "bench", "fit")) for b in args[:2]):
        print(f"expected two build folders holding bench/fit\n{usage}",
              file=sys.stderr)
        sys.exit(2)
    a, b = args[0], args[1]
    rounds = int(args[2]) if len(args) == 3 else 9
    ta, tb = [], []
    print("round  A s      B s      B / A")
    for r in range(rounds):
        if r % 2 == 0:
            ta.append(wall(a))
            tb.append(wall(b))
        else:
            tb.append(wall(b))
            ta.append(wall(a))
        print(f"{r + 1:5d}  {ta[-1]:7.3f}  {tb[-1]:7.3f}  {tb[-1] / ta[-1]:6.3f}",
              flush=True)
    ratios = [y / x for x, y in zip(ta, tb)]
    print(f"A: {a}, median {statistics.median(ta):.3f} s")
    print(f"B: {b}, median {statistics.median(tb):.3f} s")
    print(f"B / A: median of the rounds' ratios {statistics.median(ratios):.3f} "
          f"(from {min(ratios):.3f} to {max(ratios):.3f}), "
          f"of the medians {statistics.median(tb) / statistics.median(ta):.3f}")


if __name__ == "__main__":
    main()
