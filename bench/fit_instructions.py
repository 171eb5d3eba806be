#!/usr/bin/env python3
"""The default fit's instructions: a figure the machine's load does not
move, to judge a change of the fitter on a shared, noisy machine.
`bench/fit 1 --default-only` (yellow plastic under Venice, 512 px) runs
under `perf stat -e instructions:u` where the CPU's counters are
reachable, else under valgrind's callgrind (every thread's instructions,
run one at a time: some 60 times slower).  Prints the total and, from
callgrind, the share of each stage of the fit (inclusive) and the
functions that execute the most instructions themselves.  With --arm64,
the arm64 build's count too (scripts/setup-arm64 makes it; bench/fit is
built there when missing): qemu-aarch64 (Debian's qemu-user) with
glint's TCG plugin bench/qemu_insn_count.c, and from the two counts and
the fit's measured use of 2 cores here, an estimate of its time on a
Raspberry Pi 5 class CPU.  Writes docs/results/fit-instructions.md with
--write.

usage: bench/fit_instructions.py [BUILD_DIR] [--arm64 [ARM64_BUILD_DIR]] [--write]"""
import os
import resource
import re
import shutil
import subprocess
import sys
import tempfile
import time
from datetime import datetime, timezone

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "bench"))
from page import bench_args, machine, write_atomic  # noqa: E402

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
    m = re.search(r"Collected\s*:\s*(\d+)", p.stderr)
    total = int(m.group(1)) if m else None
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


# The board's CPU: a Raspberry Pi 5's Cortex-A76, 4 cores at 2.4 GHz.
# Instructions per cycle on this scalar double-precision code are not
# measured here (no such board): a range is assumed and said to be one.
PI_GHZ, PI_CORES, PI_IPC = 2.4, 4, (1.0, 1.5)


def arm64_count(build, arm_build, tmp):
    """Instructions the arm64 bench/fit retires under qemu-aarch64."""
    qemu = shutil.which("qemu-aarch64")
    if not qemu:
        sys.exit("fit_instructions: --arm64 needs qemu-aarch64 (apt install qemu-user; "
                 "qemu-user-static cannot load plugins)")
    plugin = os.path.join(build, "bench", "libqemu_insn_count.so")
    if not os.path.exists(plugin):
        sys.exit(f"fit_instructions: {plugin}: not built (ninja -C {build})")
    cache = os.environ.get("GLINT_CACHE", os.path.expanduser("~/.cache/glint"))
    sysroot = os.path.join(cache, "arm64-sysroot")
    if not os.path.isdir(sysroot) or not os.path.exists(os.path.join(arm_build, "build.ninja")):
        sys.exit(f"fit_instructions: no arm64 build in {arm_build} (scripts/setup-arm64)")
    subprocess.run(["ninja", "-C", arm_build, "bench/fit"], check=True, capture_output=True)
    log = os.path.join(tmp, "qemu.log")
    p = subprocess.run([qemu, "-L", sysroot, "-plugin", plugin, "-d", "plugin", "-D", log,
                        os.path.join(arm_build, "bench", "fit"), "1", "--default-only"],
                       capture_output=True, text=True)
    m = re.search(r"^instructions (\d+)$", open(log).read() if os.path.exists(log) else "", re.M)
    if p.returncode != 0 or not m:
        sys.exit(f"fit_instructions: the arm64 fit under qemu failed:\n{p.stderr[-2000:]}")
    return int(m.group(1))


def threads_speedup(cmd):
    """The fit's CPU time over its wall time here (2 cores): how much of
    it runs on both."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.monotonic()
    subprocess.run(cmd, check=True, capture_output=True)
    wall = time.monotonic() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return cpu / wall, wall


def pi_estimate(n_arm, s2):
    """Seconds on PI_CORES cores at PI_GHZ for each assumed IPC: Amdahl's
    law with the parallel share that gives speed-up s2 on 2 cores."""
    par = min(1.0, max(0.0, 2 * (1 - 1 / max(s2, 1.0))))
    s4 = 1 / ((1 - par) + par / PI_CORES)
    return par, s4, [(ipc, n_arm / (PI_GHZ * 1e9 * ipc * s4)) for ipc in PI_IPC]


def main():
    args = sys.argv[1:]
    bench_args(__doc__, args, ("--write", "--arm64"))
    arm_build = None
    if "--arm64" in args:
        i = args.index("--arm64")
        if i + 1 < len(args) and not args[i + 1].startswith("-"):
            arm_build = os.path.abspath(args.pop(i + 1))
        else:
            arm_build = os.path.join(ROOT, "build-arm64")
    build = os.path.abspath(next((a for a in args if not a.startswith("-")),
                                 os.path.join(ROOT, "build")))
    fit = os.path.join(build, "bench", "fit")
    if not os.access(fit, os.X_OK):
        sys.exit(f"fit_instructions: {fit}: not built (run ./scripts/setup)")
    cmd = [fit, "1", "--default-only"]
    where = machine()
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
        n_arm = arm64_count(build, arm_build, tmp) if arm_build else None
        s2, wall = threads_speedup(cmd) if arm_build else (None, None)
    lines = [f"default fit (bench/fit 1 --default-only): {n / 1e9:.2f} G instructions ({how})"]
    for name, v in stages:
        lines.append(f"  {name:50s} {v / 1e9:6.2f} G  {100 * v / n:5.1f} %")
    if top:
        lines.append("  the code that executes the most instructions itself (file: function it is in):")
        for name, v in top:
            lines.append(f"    {name:58s} {v / 1e9:6.2f} G  {100 * v / n:5.1f} %")
    if n_arm:
        par, s4, est = pi_estimate(n_arm, s2)
        lines.append(f"arm64 (qemu-aarch64 + bench/qemu_insn_count.c): {n_arm / 1e9:.2f} G "
                     f"instructions, {n_arm / n:.2f}x amd64's")
        lines.append(f"  here: {wall:.2f} s wall, CPU time {s2:.2f}x the wall on 2 cores "
                     f"(parallel share {par:.2f}; on {PI_CORES} cores {s4:.2f}x)")
        for ipc, t in est:
            lines.append(f"  estimate, Pi 5 class ({PI_CORES} x Cortex-A76 at {PI_GHZ} GHz), "
                         f"{ipc:.1f} instructions per cycle: {t:.1f} s")
    print("\n".join(lines))
    if "--write" in args:
        commit = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"],
                                capture_output=True, text=True).stdout.strip()
        when = datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
        md = ["# The default fit's instructions", "",
              f"`bench/fit_instructions.py {' '.join(sys.argv[1:])}` (commit {commit}, {when}, "
              f"{where}): `bench/fit 1 --default-only` (yellow "
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
                   "`fastmath.h: lobe_sample_block` is the polynomials "
                   "inlined into a hit's block of lobe samples):", "",
                   "| function | G instructions | share |", "|---|---:|---:|"]
            md += [f"| {s} | {v / 1e9:.2f} | {100 * v / n:.1f} % |" for s, v in top]
        if n_arm:
            md += ["", "## On the board's CPU (arm64)", "",
                   f"The arm64 build (`scripts/setup-arm64`, GCC 12 for `cortex-a76`, LTO) "
                   f"runs the same fit under `qemu-aarch64` with glint's TCG plugin "
                   f"(`bench/qemu_insn_count.c`: each translated block adds its "
                   f"instructions to a counter when it runs): **{n_arm / 1e9:.2f} G "
                   f"instructions**, {n_arm / n:.2f}× amd64's.", "",
                   f"**An estimate, not a measurement** (no such board here): the time on "
                   f"a Raspberry Pi 5 class CPU ({PI_CORES} × Cortex-A76 at {PI_GHZ} GHz) is "
                   f"the arm64 count over the clock, an assumed range of instructions per "
                   f"cycle, and the speed-up of {PI_CORES} threads by Amdahl's law with the "
                   f"parallel share measured here (the fit's CPU time {s2:.2f}× its "
                   f"{wall:.2f} s wall on 2 cores: share {par:.2f}, so {s4:.2f}× on "
                   f"{PI_CORES} cores; a loaded machine understates it).", "",
                   "| instructions per cycle (assumed) | estimated fit time |", "|---:|---:|"]
            md += [f"| {ipc:.1f} | {t:.1f} s |" for ipc, t in est]
        path = os.path.join(ROOT, "docs", "results", "fit-instructions.md")
        write_atomic(path, ("\n".join(md) + "\n").encode())
        print(f"wrote {path}")


if __name__ == "__main__":
    main()
