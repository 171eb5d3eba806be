#!/usr/bin/env python3
"""bench/coverage_terms.py on a dump whose answers are known by hand:
what it counts (not the undetermined values, not roughness reported as a
bound), each class's coverage and median |error| / sigma as fitted, and
the same with the fast render's term or roughness's noise bias replaced.

usage: bench/test_coverage_terms.py"""
import json
import os
import subprocess
import sys
import tempfile

TOOL = os.path.join(os.path.dirname(os.path.abspath(__file__)),
                    "coverage_terms.py")


def value(group, k, err, **kw):
    r = {"material": "m", "map": "x.hdr", "rot": 0, "level": "noise-free",
         "param": group, "group": group, "k": k, "truth": 0.5,
         "fit": 0.5 + err, "se": 1.0, "sys": 0.6, "sys_render": 0.6,
         "sys_fixed": 0.6, "gain_term": 0.0,
         "gain_unit": 0.0, "blocks": 0.8, "mc": 0.0, "textbook": 0.8, "t": 2.0,
         "lo": 0.5 + err - 2.0, "hi": 0.5 + err + 2.0, "bound": None,
         "range": 100.0, "truths": [0.5] * 8}
    r.update(kw)
    return r


def row(out, title, group):
    """The numbers of group's row in the table headed title."""
    part = out.split(title, 1)[1].split("\n\n", 1)[0]
    for line in part.splitlines():
        f = line.split()
        if f[:2] == ["noise-free", group]:
            return int(f[2]), float(f[3].rstrip("%")), float(f[4]), f[5]
    return None


def main():
    if len(sys.argv) > 1:
        print(__doc__.splitlines()[-1])
        return 0 if sys.argv[1] in ("-h", "--help") else 2
    errs = [0.1 * i for i in range(1, 10)] + [2.5]
    rows = [value("diffuse", 0, e) for e in errs]
    # not determined, and a roughness reported as an upper bound: apart
    rows.append(value("diffuse", 1, 0.3, se=None, lo=0.0, hi=100.0))
    rows.append(value("roughness", 6, 5.0, bound=0.9))
    # a roughness of 0.2 (its noise bias: 2 x its statistical part)
    # (and a gain term at K 1 of 5, which glint does not take for it)
    rows.append(value("roughness", 6, 1.0, truth=0.2 - 1.0, fit=0.2,
                      gain_unit=5.0))
    # a specular value whose render term is all gain: 0.6 at K 1
    rows.append(value("specular", 3, 1.0, sys_fixed=0.0, gain_unit=0.6,
                      gain_term=0.6))
    # another map's value: counted with the rest, not under --map x.hdr
    rows.append(value("ior", 7, 3.0, map="y.hdr", mc=0.5))
    fails = 0

    def check(cond, what):
        nonlocal fails
        if not cond:
            print("FAIL", what)
            fails += 1

    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "dump.jsonl")
        with open(path, "w") as f:
            for r in rows:
                f.write(json.dumps(r) + "\n")

        def run(*extra):
            p = subprocess.run([sys.executable, TOOL, path, *extra],
                               capture_output=True, text=True)
            check(p.returncode == 0, f"{extra}: exit {p.returncode} "
                  f"{p.stderr}")
            return p.stdout

        out = run()
        # |e| <= t se for 9 of 10; the median of 0.1 .. 0.9, 2.5 is 0.5
        check(row(out, "as fitted", "diffuse") == (10, 90.0, 0.5, "met"),
              f"as fitted, diffuse: {row(out, 'as fitted', 'diffuse')}")
        check(row(out, "as fitted", "roughness") == (1, 100.0, 1.0,
                                                       "missed"),
              f"as fitted, roughness: {row(out, 'as fitted', 'roughness')}")
        check("with the terms given" not in out, "no terms, no second table")
        check(row(out, "as fitted", "ior") == (1, 0.0, 3.0, "missed"),
              f"the other map's value: {row(out, 'as fitted', 'ior')}")
        out = run("--map", "x.hdr")
        check(row(out, "as fitted", "ior") is None and
              row(out, "as fitted", "diffuse") == (10, 90.0, 0.5, "met"),
              "--map x.hdr: that map's values alone")
        # K x the sets' part in every class's term: ior's 0.5 x 8 = 4
        # beside its statistical 0.8, sigma 4.08 (one value covered of
        # one: above the target's 98 %)
        out = run("--sampling", "8")
        check(row(out, "with the terms given", "ior") ==
              (1, 100.0, 0.74, "missed"),
              f"--sampling 8, ior: {row(out, 'with the terms given', 'ior')}")
        out = run("--diffuse", "0", "0", "--roughness", "0", "1")
        given = "with the terms given"
        # without the term: sigma 0.8 (the statistical part), 9 of 10
        # within 1.6, median 0.5 / 0.8
        check(row(out, given, "diffuse") == (10, 90.0, 0.62, "met"),
              f"no term, diffuse: {row(out, given, 'diffuse')}")
        # noise bias 1 x 0.2 / 0.1 = 2: sigma 0.8 sqrt(5)
        check(row(out, given, "roughness") == (1, 100.0, 0.56, "missed"),
              f"noise bias, roughness: {row(out, given, 'roughness')}")
        # the gain term replaced: none leaves the statistical 0.8; K 2
        # gives 1.2, sigma sqrt(0.64 + 1.44)
        check(row(out, "as fitted", "specular") == (1, 100.0, 1.0, "missed"),
              f"as fitted, specular: {row(out, 'as fitted', 'specular')}")
        check(row(run("--gain", "0"), given, "specular") ==
              (1, 100.0, 1.25, "missed"), "--gain 0, specular")
        out = run("--gain", "2")
        check(row(out, given, "specular") == (1, 100.0, 0.69, "missed"),
              "--gain 2, specular")
        check(row(out, given, "roughness") == (1, 100.0, 1.0, "missed"),
              "--gain 2 leaves roughness as fitted")
        out = run("--diffuse", "0", "2")
        # sigma sqrt(0.64 + 4): every value covered, median 0.23
        check(row(out, given, "diffuse") == (10, 100.0, 0.23, "missed"),
              f"a wide term, diffuse: {row(out, given, 'diffuse')}")
        check(row(out, given, "roughness") == (1, 100.0, 1.0, "missed"),
              "a class not given keeps its terms")
        p = subprocess.run([sys.executable, TOOL, path, "--ior", "x"],
                           capture_output=True, text=True)
        check(p.returncode == 2 and "--ior: takes 1 numbers" in p.stderr,
              f"a bad number: exit {p.returncode} {p.stderr}")
        p = subprocess.run([sys.executable, TOOL, path, "--sampling", "2",
                            "--ior", "1"], capture_output=True, text=True)
        check(p.returncode == 2, "--sampling with another term refused")
        with open(path, "w") as f:
            f.write('{"map": "x.hdr"}\n')
        p = subprocess.run([sys.executable, TOOL, path], capture_output=True,
                           text=True)
        check(p.returncode != 0 and "dump.jsonl:1: not a line of "
              "COVERAGE_DUMP (no level" in p.stderr,
              f"a line without its fields: {p.stderr}")
        with open(path, "w") as f:
            f.write("not json\n")
        p = subprocess.run([sys.executable, TOOL, path], capture_output=True,
                           text=True)
        check(p.returncode != 0 and "dump.jsonl:1: not a line of "
              "COVERAGE_DUMP" in p.stderr, f"a bad dump: {p.stderr}")
    if not fails:
        print("ok: bench/coverage_terms.py counts, replays and refuses as "
              "worked out by hand")
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())
