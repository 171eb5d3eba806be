#!/usr/bin/env python3
"""A benchmark's results as a page: runs the benchmark, and writes what it
printed (its tables) and its chart into docs/results/NAME.md and NAME.png,
headed by the command, the machine, the date and the commit, so that
re-running the benchmark regenerates the page and nothing is copied by
hand.  The chart is the PNG the benchmark wrote as bench-out/NAME.png
(or the one given with --png).  A benchmark that fails writes no page.

usage: bench/page.py [--out-dir DIR] [--png FILE] NAME -- COMMAND [ARG...]"""
import os
import platform
import shlex
import subprocess
import sys
import tempfile
import time
from datetime import datetime, timezone

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
USAGE = __doc__.splitlines()[-1]


def refuse(what):
    print(f"{what}\n{USAGE}", file=sys.stderr)
    sys.exit(2)


def bench_args(doc, args, takes=()):
    """A benchmark's usage (its docstring's last line): printed with exit 0
    for -h or --help, and with exit 2 after naming the first option in
    args that is not in takes."""
    usage = doc.splitlines()[-1]
    if "-h" in args or "--help" in args:
        print(usage)
        sys.exit(0)
    unknown = [a for a in args if a.startswith("-") and a not in takes]
    if unknown:
        print(f"{unknown[0]}: not an argument of this benchmark\n{usage}",
              file=sys.stderr)
        sys.exit(2)
    return usage


def write_atomic(path, data):
    """path holds data whole or keeps what it held: written beside it,
    then renamed over it."""
    fd, tmp = tempfile.mkstemp(dir=os.path.dirname(path) or ".", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except BaseException:
        os.unlink(tmp)
        raise


def machine():
    cores = os.cpu_count()
    model = ""
    try:
        with open("/proc/cpuinfo") as f:
            model = next((l.split(":", 1)[1].strip() for l in f if l.startswith("model name")), "")
    except OSError:
        pass
    load = os.getloadavg()[0]
    return f"{platform.machine()}, {cores} cores{', ' + model if model else ''}, load {load:.1f} at the start"


def main():
    args = sys.argv[1:]
    if not args or args[0] in ("-h", "--help"):
        print(USAGE)
        return
    out_dir, png = os.path.join(ROOT, "docs", "results"), None
    while args and args[0].startswith("-") and args[0] != "--":
        if args[0] in ("--out-dir", "--png") and len(args) > 1:
            if args[0] == "--out-dir":
                out_dir = args[1]
            else:
                png = args[1]
            args = args[2:]
        else:
            refuse(f"{args[0]}: not an argument of bench/page.py")
    if len(args) < 3 or args[1] != "--":
        refuse("expected NAME -- COMMAND")
    name, cmd = args[0], args[2:]
    if not name.replace("-", "").replace("_", "").isalnum():
        refuse(f"{name}: a page name is letters, digits, - and _")
    png = png or os.path.join("bench-out", name + ".png")
    commit = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"],
                            capture_output=True, text=True).stdout.strip() or "unknown"
    dirty = subprocess.run(["git", "-C", ROOT, "status", "--porcelain", "--untracked-files=no"],
                           capture_output=True, text=True).stdout.strip()
    header_machine = machine()
    start = datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    t0 = time.monotonic()
    png_before = os.path.getmtime(png) if os.path.exists(png) else None
    p = subprocess.run(cmd, stdout=subprocess.PIPE, text=True)
    seconds = time.monotonic() - t0
    if p.returncode != 0:
        print(f"bench/page.py: {' '.join(cmd)} failed (exit {p.returncode}): no page written",
              file=sys.stderr)
        sys.exit(1)
    sys.stdout.write(p.stdout)
    os.makedirs(out_dir, exist_ok=True)
    fresh_png = os.path.exists(png) and os.path.getmtime(png) != png_before
    lines = [f"# {name}", "",
             f"`bench/page.py {name} -- {shlex.join(cmd)}`: run {start} on {header_machine}, "
             f"commit {commit}{' with local changes' if dirty else ''}, {seconds:.0f} s. "
             "Regenerate the page with the same command; what the benchmark measures "
             "and why: [benchmarks.md](../benchmarks.md).", ""]
    if fresh_png:
        lines += [f"![{name}]({name}.png)", ""]
    lines += ["```", p.stdout.rstrip("\n"), "```", ""]
    page, chart = os.path.join(out_dir, name + ".md"), os.path.join(out_dir, name + ".png")
    if fresh_png:
        with open(png, "rb") as f:
            write_atomic(chart, f.read())
    elif os.path.exists(chart) and os.path.exists(page) and f"({name}.png)" in open(page).read():
        os.remove(chart)  # the chart of this page's earlier run, not of this one
    write_atomic(page, "\n".join(lines).encode())
    print(f"wrote {os.path.join(out_dir, name + '.md')}", file=sys.stderr)


if __name__ == "__main__":
    main()
