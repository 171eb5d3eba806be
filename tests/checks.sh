# Shell tests' checks, counted and reported one line each.  Source it
# after setting $glint (the binary) and $tmp (the test's scratch folder):
#   . "$(dirname "$0")/../checks.sh"
#   check "what is checked" COMMAND...    ok/FAIL line, counted
#   run EXIT STDERR_FRAGMENT ARGS...      glint ARGS exits EXIT, its stderr
#                                         holds the fragment ("": any);
#                                         stdout in $tmp/out, stderr $tmp/err
#   checks_done                           the tally; exit status 1 on a FAIL
fails=0 checks=0
check() {
	local what=$1
	shift
	checks=$((checks + 1))
	if "$@"; then echo "ok   $what"; else echo "FAIL $what"; fails=$((fails + 1)); fi
}
run() {
	local want=$1 frag=$2
	shift 2
	"$glint" "$@" >"$tmp/out" 2>"$tmp/err"
	local got=$?
	[ "$got" = "$want" ] || { echo "  glint $*: exit $got, expected $want:" >&2; cat "$tmp/err" >&2; return 1; }
	[ -z "$frag" ] || grep -qF -- "$frag" "$tmp/err" || { echo "  stderr lacks '$frag':" >&2; cat "$tmp/err" >&2; return 1; }
}
checks_done() {
	echo "$((checks - fails))/$checks checks passed"
	[ "$fails" = 0 ]
}
