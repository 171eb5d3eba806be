#!/usr/bin/env python3
"""The first press, timed by stage: `glint rig --once` on the shipped
simulated rig, one cold round (the camera's views rendered and cached)
and then ROUNDS warm ones, each stage's median over the warm rounds and
the whole from the press to the printed result; the peak memory of the
processes.  Stages are read off the run's own JSON log lines (their UTC
times), so the breakdown is glint's own account of where the time went.
Writes docs/results/first-press.md and, from the last round's fit, its
compare.png (photo | render | render - photo) as first-press.png, the
README's picture (with --write).

usage: bench/first_press.py [BUILD_DIR] [--rounds N] [--write]"""
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from datetime import datetime

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# (stage, the message that starts it); each stage ends where the next
# starts, the last at the printed result.
MARKS = [
    ("board: lights, turntable to the probe", "button pressed: starting a run"),
    ("probe: bracket and merge", "capturing the probe"),
    ("probe: ball found, unwrapped", "probe ball at"),
    ("board: turntable to the sample", "step 4/"),
    ("sample: bracket, merge, sphere, scene", "capturing the sample"),
    ("queue: fit queued, worker started", "step 6/"),
    ("fit", ": fitting "),
    ("result printed", ": done (the fit's peak memory"),
]


def stamp(line):
    return datetime.strptime(line["time"], "%Y-%m-%dT%H:%M:%S.%fZ").timestamp()


def one_round(glint, rig, cache):
    env = dict(os.environ, GLINT_SIM_CACHE=cache)
    t_start = time.time()
    p = subprocess.run([glint, "rig", "--config", rig, "--once", "--json"],
                       capture_output=True, text=True, env=env)
    t_end = time.time()
    if p.returncode != 0:
        sys.exit(f"first_press: glint rig --once failed:\n{p.stderr[-2000:]}")
    logs = [json.loads(l) for l in p.stderr.splitlines() if l.startswith("{")]
    at = []
    for name, frag in MARKS:
        t = next((stamp(l) for l in logs if frag in l.get("msg", "")), None)
        if t is None:
            sys.exit(f"first_press: no log line with '{frag}'")
        at.append(t)
    at.append(t_end)
    stages = {name: at[k + 1] - at[k] for k, (name, _) in enumerate(MARKS)}
    # inside the fit, from its params.json: the fit proper and the final
    # render (render.exr, within half the fit's time)
    res = json.loads(p.stdout)
    fit = json.load(open(os.path.join(res["sample"], "fit", "params.json")))
    stages["  of it: fitting (params.json seconds)"] = fit["seconds"]
    stages["  of it: render.exr, within half the fit's time"] = fit["render"]["seconds"]
    stages["press to printed result"] = t_end - at[0]
    stages["process, start to end"] = t_end - t_start
    with open(os.path.join(res["sample"], "fit", "compare.png"), "rb") as f:
        stages["compare.png"] = f.read()
    return stages


def main():
    args = sys.argv[1:]
    build = next((a for a in args if not a.startswith("--") and not a.isdigit()),
                  os.path.join(ROOT, "build"))
    rounds = int(args[args.index("--rounds") + 1]) if "--rounds" in args else 5
    glint = os.path.join(build, "cmd", "glint")
    with tempfile.TemporaryDirectory() as tmp:
        r = json.load(open(os.path.join(ROOT, "data", "rig-sim.json")))
        r["output"] = os.path.join(tmp, "out")
        r["board"]["scenario"] = os.path.join(ROOT, "data", "sim-press.json")
        rig = os.path.join(tmp, "rig.json")
        json.dump(r, open(rig, "w"))
        cache = os.path.join(tmp, "cache")
        cold = one_round(glint, rig, cache)
        warm = [one_round(glint, rig, cache) for _ in range(rounds)]
    picture = warm[-1]["compare.png"] if warm else cold["compare.png"]
    for st in [cold] + warm:
        del st["compare.png"]
    peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
    names = list(cold)
    rows = ["| stage | cold (views rendered) | warm, median of %d | warm, min .. max |" % rounds,
            "|---|---:|---:|---:|"]
    for n in names:
        v = [w[n] for w in warm]
        rows.append(f"| {n} | {cold[n]:.2f} s | {statistics.median(v):.2f} s | "
                    f"{min(v):.2f} .. {max(v):.2f} s |")
    text = "\n".join(rows)
    print(text)
    print(f"peak memory of one process: {peak:.0f} MiB; {os.cpu_count()} cores; "
          f"load {os.getloadavg()[0]:.1f}")
    if "--write" in args:
        with open(os.path.join(ROOT, "docs", "results", "first-press.md"), "w") as f:
            f.write("# The first press, by stage\n\n"
                    "`bench/first_press.py --write`: `glint rig --once` on the shipped\n"
                    "simulated rig (`data/rig-sim.json`), once with the camera's views\n"
                    "not yet cached and %d times with them cached; each stage from the\n"
                    "run's own log.  Seconds of wall-clock time on %d cores (load %.1f\n"
                    "when written); the peak memory of one glint process %.0f MiB.\n\n"
                    % (rounds, os.cpu_count(), os.getloadavg()[0], peak))
            f.write(text + "\n\nCold, the camera renders the view in sight (the probe) before\n"
                    "its bracket and the sample's on a thread of its own meanwhile; the\n"
                    "probe's capture waits for that thread when it closes the camera,\n"
                    "which is the cold unwrap stage's extra time.\n"
                    "\nThe last round's fit, its `compare.png`: the photo, the render of\n"
                    "the fitted material, and render − photo (blue darker, red brighter;\n"
                    "the scale bar in the photo's units):\n\n"
                    "![photo, render, render - photo](first-press.png)\n")
        with open(os.path.join(ROOT, "docs", "results", "first-press.png"), "wb") as f:
            f.write(picture)


if __name__ == "__main__":
    main()
