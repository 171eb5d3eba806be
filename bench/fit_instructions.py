#!/usr/bin/env python3
"""The default fit's instructions: a figure the machine's load does not
move, to judge a change of the fitter on a shared, noisy machine.
`bench/fit 1 --default-only` (yellow plastic under Venice, 512 px) runs
under `perf stat -e instructions:u` where the CPU's counters are
reachable, else under valgrind's callgrind (every thread's instructions,
run one at a time: some 60 times slower).  Prints the total and, from
callgrind, the share of each stage of the fit (inclusive) and the
functions that execute the most instructions themselves.  Writes
docs/results/fit-instructions.md with --write.

usage: bench/fit_instructions.py [BUILD_DIR] [--write]"""
import os
import platform
import re
import shutil
import subprocess
import sys
import tempfile
from datetime import datetime, timezone

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# The stage rows of bench/fit --default-only's table (seconds).  Under
# callgrind the threads run one at a time at a near-constant rate, so each
# stage's share of that run's time is its share of the instructions.
STAGE_ROW = re.compile(r"^  (\d \w+|fine|3 sample sets|uncertainty \(with the sets\)|"
                       r"set-up \(data, first cache\)|the rest \(scans, statistics\))"
                       r"\s+(?:\d+\s+\d+\s+\d+\s+)?([\d.]+)$")


def stage_shares(stdout):
    rows = [(m.group(1), float(m.group(2))) for m in map(STAGE_ROW.match, stdout.splitlines()) if m]
    wall = re.search(r"^  wall\s+([\d.]+)$", stdout, re.M)
    if not rows or not wall:
        return []
    label = {"1 diffuse": "pass 1 (diffuse, coarse)", "2 specular": "pass 2 (specular, coarse)",
             "3 all": "pass 3 (all, coarse)", "fine": "fine pass",
             "3 sample sets": "of the uncertainty: the polish on 3 sample sets",
             "uncertainty (with the sets)": "uncertainty (with the sets)"}
    out = [(label.get(name, name), t / float(wall.group(1))) for name, t in rows]
    # the polish is part of the uncertainty stage: list it under it
    polish = [r for r in out if r[0].startswith("of the uncertainty")]
    out = [r for r in out if r not in polish]
    at = next((i + 1 for i, r in enumerate(out) if r[0].startswith("uncertainty")), len(out))
    return out[:at] + polish + out[at:]


def perf_count(cmd):
    """Instructions from the PMU, or None where perf cannot count them."""
    if not shutil.which("perf"):
        return None
    p = subprocess.run(["perf", "stat", "-x,", "-e", "instructions:u"] + cmd,
                       capture_output=True, text=True)
    for line in p.stderr.splitlines():
        f = line.split(",")
        if len(f) > 2 and f[2].startswith("instructions") and f[0].isdigit():
            return int(f[0])
    return None


def callgrind(cmd, tmp):
    out = os.path.join(tmp, "callgrind.out")
    p = subprocess.run(["valgrind", "--tool=callgrind", "--callgrind-out-file=" + out] + cmd,
                       capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"fit_instructions: {' '.join(cmd)} under valgrind failed:\n{p.stderr[-2000:]}")
    total = int(re.search(r"Collected\s*:\s*(\d+)", p.stderr).group(1)) \
        if re.search(r"Collected\s*:\s*(\d+)", p.stderr) else None
    self_ = subprocess.run(["callgrind_annotate", out], capture_output=True, text=True).stdout
    row = re.compile(r"^\s*([\d,]+)\s+\([\s\d.]+%\)\s+(\S+):(\S+)")
    if total is None:
        m = re.search(r"^\s*([\d,]+)\s+\(100.0%\)\s+PROGRAM TOTALS", self_, re.M)
        total = int(m.group(1).replace(",", ""))
    stages = [(name, share * total) for name, share in stage_shares(p.stdout)]
    top = []
    for line in self_.splitlines():
        m = row.match(line)
        if m and len(top) < 12:
            where = os.path.basename(m.group(2))
            top.append((f"{where}: {m.group(3).split('.')[0]}", int(m.group(1).replace(",", ""))))
    return total, stages, top


def main():
    args = sys.argv[1:]
    usage = __doc__.splitlines()[-1]
    if "-h" in args or "--help" in args:
        print(usage)
        return
    unknown = [a for a in args if a.startswith("-") and a != "--write"]
    if unknown:
        print(f"{unknown[0]}: not an argument of this benchmark\n{usage}", file=sys.stderr)
        sys.exit(2)
    build = next((a for a in args if not a.startswith("-")), os.path.join(ROOT, "build"))
    fit = os.path.join(build, "bench", "fit")
    if not os.access(fit, os.X_OK):
        sys.exit(f"fit_instructions: {fit}: not built (run ./scripts/setup)")
    cmd = [fit, "1", "--default-only"]
    with tempfile.TemporaryDirectory() as tmp:
        # bench/fit caches its reference photo in ./bench-out: run where
        # the checkout's cache is.
        os.chdir(ROOT)
        n = perf_count(cmd)
        how = "perf stat -e instructions:u"
        stages, top = [], []
        if n is None:
            if not shutil.which("valgrind"):
                sys.exit("fit_instructions: neither perf's counters nor valgrind here")
            n, stages, top = callgrind(cmd, tmp)
            how = "valgrind --tool=callgrind"
    lines = [f"default fit (bench/fit 1 --default-only): {n / 1e9:.2f} G instructions ({how})"]
    for name, v in stages:
        lines.append(f"  {name:50s} {v / 1e9:6.2f} G  {100 * v / n:5.1f} %")
    if top:
        lines.append("  the code that executes the most instructions itself (file: function it is in):")
        for name, v in top:
            lines.append(f"    {name:58s} {v / 1e9:6.2f} G  {100 * v / n:5.1f} %")
    print("\n".join(lines))
    if "--write" in args:
        commit = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"],
                                capture_output=True, text=True).stdout.strip()
        when = datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
        md = ["# The default fit's instructions", "",
              f"`bench/fit_instructions.py --write` (commit {commit}, {when}, "
              f"{platform.machine()}): `bench/fit 1 --default-only` (yellow "
              f"plastic under Venice, a 512×512 photo, sphere radius 180 px) "
              f"counted by `{how}`. The count does not move with the "
              f"machine's load, so a change to the fitter is judged by it "
              f"where seconds are noise.", "",
              f"**{n / 1e9:.2f} G instructions** in all (every thread; the "
              f"reference photo read from bench-out/: where it is absent, "
              f"its one-time render counts too).", ""]
        if stages:
            md += ["Each stage's share of the run under callgrind's serial, "
                   "near-constant rate (the stages of `bench/fit --default-only`; "
                   "the sample sets' polish is part of the uncertainty stage):", "",
                   "| stage | G instructions | share |", "|---|---:|---:|"]
            md += [f"| {s} | {v / 1e9:.2f} | {100 * v / n:.1f} % |" for s, v in stages]
            md += ["", "The code that executes the most instructions itself, as "
                   "callgrind attributes it (`file: function`; code inlined from "
                   "a file counts under the function it was inlined into, so "
                   "`envmap.c: lobe_sample` is the map lookup inside a lobe "
                   "sample):", "",
                   "| function | G instructions | share |", "|---|---:|---:|"]
            md += [f"| {s} | {v / 1e9:.2f} | {100 * v / n:.1f} % |" for s, v in top]
        path = os.path.join(ROOT, "docs", "results", "fit-instructions.md")
        with open(path, "w") as f:
            f.write("\n".join(md) + "\n")
        print(f"wrote {path}")


if __name__ == "__main__":
    main()
