#!/usr/bin/env bash
# Each benchmark answers --help with its usage and exit 0 before any work,
# and refuses an argument it does not take with exit 2 and its usage (a
# mistyped option once started bench/fit's 12-minute full run).
#   bench/test_args.sh BENCH...
set -u
fail=0
for b in "$@"; do
	name=$(basename "$b")
	out=$(timeout 10 "$b" --help 2>&1)
	rc=$?
	if [ "$rc" != 0 ] || [[ "$out" != "usage: bench/$name"* ]]; then
		echo "FAIL $name --help: exit $rc, output: $out"
		fail=1
	fi
	out=$(timeout 10 "$b" --no-such-option 2>&1)
	rc=$?
	if [ "$rc" != 2 ] || [[ "$out" != *"--no-such-option: not an argument"*"usage: bench/$name"* ]]; then
		echo "FAIL $name --no-such-option: exit $rc, output: $out"
		fail=1
	fi
done
[ "$fail" = 0 ] && echo "ok: $# benchmarks answer --help and refuse an unknown option"
exit $fail
