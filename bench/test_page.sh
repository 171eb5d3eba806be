#!/usr/bin/env bash
# bench/page.py writes a benchmark's output and chart as a page headed by
# the command, machine, date and commit; a failing benchmark writes none.
#   bench/test_page.sh
set -u
page=$(cd "$(dirname "$0")" && pwd)/page.py
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
cd "$tmp" || exit 1
mkdir bench-out
check() { # what condition...
	local what=$1
	shift
	if "$@"; then echo "ok   $what"; else echo "FAIL $what"; fail=1; fi
}
"$page" --out-dir out --png chart.png demo -- \
	sh -c "printf 'mode  wall\nfast  1.0 s\n'; printf 'the chart' >chart.png" >/dev/null 2>&1
check "page written" test -f out/demo.md
check "... its header names the command and the commit" \
	grep -q "^\`bench/page.py demo -- sh -c" out/demo.md
check "... and the commit" grep -Eq "commit [0-9a-f]{7,}|commit unknown" out/demo.md
check "... the output in a code block" grep -q '^fast  1.0 s$' out/demo.md
check "... the chart beside it, linked" bash -c "cmp -s chart.png out/demo.png && grep -q '(demo.png)' out/demo.md"
"$page" --out-dir out failing -- sh -c 'echo half a table; exit 3' >/dev/null 2>&1
check "a failing benchmark: exit 1" test $? = 1
check "... and no page" test ! -e out/failing.md
"$page" --out-dir out demo -- printf 'second run\n' >/dev/null 2>&1
check "a second run replaces the page; a chart it did not make is neither linked nor kept" \
	bash -c "grep -q '^second run$' out/demo.md && ! grep -q '(demo.png)' out/demo.md && test ! -e out/demo.png"
printf 'a user chart' >out/mine.png
"$page" --out-dir out mine -- printf 'a table\n' >/dev/null 2>&1
check "a chart no earlier page of that name linked is the user's: kept" \
	bash -c "test \"\$(cat out/mine.png)\" = 'a user chart'"
"$page" --no-such >/dev/null 2>&1
check "an unknown option: exit 2" test $? = 2
check "no temporary files left" bash -c "! ls out | grep -q '^tmp'"
exit $fail
