#!/usr/bin/env bash
# Fuzz one harness for a fixed time on its corpus (the fuzz suite with
# -Dfuzz=true, and long campaigns: scripts/fuzz).  New inputs and crash
# artifacts go to a scratch folder, never into the checkout; a crash fails
# the run and names the input to add to tests/fuzz/regressions/TARGET/.
#   fuzz_run.sh HARNESS SECONDS CORPUS REGRESSIONS [SCRATCH]
set -euo pipefail
harness=$1 seconds=$2 corpus=$3 regress=$4
scratch=${5:-$(mktemp -d)}
[ -n "${5:-}" ] || trap 'rm -rf "$scratch"' EXIT
mkdir -p "$scratch/new" "$scratch/crashes"
dirs=("$scratch/new" "$corpus")
[ -d "$regress" ] && dirs+=("$regress")
set +e
"$harness" -max_total_time="$seconds" -rss_limit_mb=2048 -timeout=10 \
	-print_final_stats=1 -artifact_prefix="$scratch/crashes/" \
	"${dirs[@]}" 2>"$scratch/log"
rc=$?
set -e
execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$scratch/log" | tail -1)
rss=$(sed -n 's/^stat::peak_rss_mb: *//p' "$scratch/log" | tail -1)
cov=$(grep -oE "cov: [0-9]+" "$scratch/log" | tail -1 | cut -d' ' -f2)
echo "fuzz $(basename "$harness"): ${execs:-0} executions (budget $seconds s), coverage ${cov:-0} edges, peak ${rss:-0} MB"
if [ "$rc" != 0 ]; then
	tail -40 "$scratch/log" >&2
	keep=$(mktemp -d "${TMPDIR:-/tmp}/glint-fuzz-crash.XXXXXX")
	cp "$scratch"/crashes/* "$keep"/ 2>/dev/null || true
	echo "fuzz: $(basename "$harness") failed; inputs kept in $keep" >&2
	exit 1
fi
