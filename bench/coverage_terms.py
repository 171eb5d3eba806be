#!/usr/bin/env python3
"""The coverage study's intervals, read back from its fits, and what other
sizes of the fast render's systematic terms would make of them, with no
refit: the terms enter only the interval's width (fit/discrepancy.c,
fit_systematic(); fit/render_gain.c), so each value's other parts, as the
study's dump states them, stay what they were.

    COVERAGE_DUMP=FILE ./build/tests/test_coverage full MAP...

Prints, per noise level and parameter class, the values counted (those the
photo determines, roughness not reported as an upper bound), the share of
95 % intervals that hold the truth and the median |error| / standard error
(an honest interval: about 0.67), as fitted; then, for the terms given,
the same with them replaced.  A class given gets a fixed term of REL of
the value with an absolute FLOOR (albedos), and for roughness m, beside
REL, NOISE x m / 0.1 times its statistical standard error (a bias that
grows with the noise and the lobe's width, which the linearised spread
does not show; 0: none).  --gain K sizes the albedos' and ior's gain
term at K times the fast render's gain error per region, as the fit's
residual showed it, carried to the value (fit/render_gain.c; glint takes
3, and none for roughness; 0: none).  What is not given keeps what it was
fitted with.  --sampling K puts K times each value's sample-sets part
(the fit's own sampling spread) in every class's terms instead.  Per
class, whether the target (90-98 % and 0.4-0.9) is met.  --map NAME
counts the values of that map (its file name) alone: the terms that suit
one light need not suit another (docs/tests.md, "Coverage").

usage: bench/coverage_terms.py FILE [--map NAME] [--diffuse REL FLOOR] [--specular REL FLOOR] [--roughness REL NOISE] [--ior REL] [--gain K] [--sampling K]"""
import json
import math
import sys

LEVELS = ["noise-free", "10k e-", "1k e-"]
GROUPS = ["diffuse", "specular", "roughness", "ior"]


KEYS = ("map", "level", "group", "truth", "fit", "se", "sys", "sys_render",
        "sys_fixed", "gain_term", "gain_unit", "mc",
        "t", "lo", "hi", "bound", "range")


def load(path, only_map=None):
    """The dump's values the study counts (of only_map's file alone when
    given), each with its statistical part and the systematic parts other
    than the fast render's term."""
    rows = []
    with open(path) as f:
        for n, line in enumerate(f, 1):
            try:
                r = json.loads(line)
                missing = [k for k in KEYS if k not in r]
            except (json.JSONDecodeError, TypeError) as e:
                sys.exit(f"{path}:{n}: not a line of COVERAGE_DUMP ({e})")
            if missing:
                sys.exit(f"{path}:{n}: not a line of COVERAGE_DUMP "
                         f"(no {', '.join(missing)})")
            if only_map is not None and r["map"] != only_map:
                continue
            se, lo, hi = r["se"], r["lo"], r["hi"]
            if se is None or lo is None or hi is None or \
                    hi - lo >= 0.5 * r["range"]:
                continue  # not determined
            if r["bound"] is not None:
                continue  # roughness below the footprint: a bound
            r["stat2"] = max(0.0, se * se - r["sys"] ** 2)
            r["other2"] = max(0.0, r["sys"] ** 2 - r["sys_render"] ** 2)
            rows.append(r)
    if not rows:
        sys.exit(f"{path}: no values the study counts" +
                 (f" under {only_map}" if only_map is not None else ""))
    return rows


def sigma(terms, r):
    """Value r's standard error with the given terms in place of its
    own: its statistical part (times 1 + the noise bias squared), the
    systematic parts that are not the fast render's, the fixed term and
    the gain term."""
    g, p = r["group"], abs(r["fit"])
    fixed, bias, gain = r["sys_fixed"], 0.0, r["gain_term"]
    if "sampling" in terms:
        fixed, bias, gain = terms["sampling"][0] * r["mc"], 0.0, 0.0
    elif g in terms:
        if g in ("diffuse", "specular"):
            fixed = math.hypot(terms[g][0] * p, terms[g][1])
        elif g == "roughness":
            fixed, bias = terms[g][0] * p, terms[g][1] * p / 0.1
        else:
            fixed = terms[g][0] * p
    if "gain" in terms and g != "roughness":
        gain = terms["gain"][0] * r["gain_unit"]
    return math.sqrt(r["stat2"] * (1 + bias * bias) + r["other2"] +
                     fixed * fixed + gain * gain)


def table(rows, sigma, title):
    print(title)
    print(f"{'noise':11} {'class':10} {'values':>6} {'covered':>8} "
          f"{'med|e|/se':>9}  target 90-98 %, 0.4-0.9")
    for lv in LEVELS:
        for g in GROUPS:
            sel = [r for r in rows if r["level"] == lv and r["group"] == g]
            if not sel:
                continue
            z = sorted(abs(r["fit"] - r["truth"]) / sigma(r) for r in sel)
            cov = sum(abs(r["fit"] - r["truth"]) <= r["t"] * sigma(r)
                      for r in sel) / len(sel)
            med = z[(len(z) - 1) // 2]
            met = 0.9 <= cov <= 0.98 and 0.4 <= med <= 0.9
            print(f"{lv:11} {g:10} {len(sel):6d} {100 * cov:7.1f}% "
                  f"{med:9.2f}  {'met' if met else 'missed'}")


NARGS = {"--diffuse": 2, "--specular": 2, "--roughness": 2, "--ior": 1,
         "--gain": 1, "--sampling": 1}


def parse(args, usage):
    """(dump path, {class: its numbers}, map or None); exit 2 naming what
    is wrong."""
    def refuse(what):
        print(f"{what}\n{usage}", file=sys.stderr)
        sys.exit(2)

    path, terms, only_map, i = None, {}, None, 0
    while i < len(args):
        a = args[i]
        if a == "--map":
            if i + 1 >= len(args):
                refuse("--map: takes a map's file name")
            only_map, i = args[i + 1], i + 2
        elif a in NARGS:
            vals = args[i + 1:i + 1 + NARGS[a]]
            try:
                nums = [float(v) for v in vals]
            except ValueError:
                nums = []
            if len(nums) != NARGS[a] or any(not x >= 0 for x in nums):
                refuse(f"{a}: takes {NARGS[a]} numbers, 0 or more")
            terms[a[2:]] = nums
            i += 1 + NARGS[a]
        elif a.startswith("-"):
            refuse(f"{a}: not an argument of this benchmark")
        elif path is None:
            path, i = a, i + 1
        else:
            refuse(f"{a}: one dump file only")
    if path is None:
        refuse("no dump file given")
    if "sampling" in terms and len(terms) > 1:
        refuse("--sampling: replaces every class's term, alone")
    return path, terms, only_map


def main():
    usage = __doc__.splitlines()[-1]
    args = sys.argv[1:]
    if "-h" in args or "--help" in args:
        print(usage)
        return
    path, terms, only_map = parse(args, usage)
    try:
        rows = load(path, only_map)
    except OSError as e:
        sys.exit(f"{path}: {e.strerror}")
    table(rows, lambda r: r["se"], "as fitted")
    if terms:
        print()
        table(rows, lambda r: sigma(terms, r), "with the terms given")


if __name__ == "__main__":
    main()
