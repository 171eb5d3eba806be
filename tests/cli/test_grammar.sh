#!/bin/bash
# One option grammar: every command, and every subcommand,
# takes --help, --json, -q, -v; a bad or misspelt flag is one line naming
# it (with the likeliest meant), then "Try 'glint CMD --help'." and exit 2.
# usage: test_grammar.sh GLINT DATA_DIR
set -u
glint=$1
data=$2
export ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}verify_asan_link_order=0"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fails=0 checks=0
check() {
	local what=$1
	shift
	checks=$((checks + 1))
	if "$@"; then
		echo "ok   $what"
	else
		echo "FAIL $what"
		fails=$((fails + 1))
	fi
}
# g EXPECTED-STATUS ARGS...: run glint, keep out and err
g() {
	local want=$1
	shift
	"$glint" "$@" >"$tmp/out" 2>"$tmp/err" </dev/null
	local got=$?
	if [ "$got" != "$want" ]; then
		echo "  glint $*: exit $got, expected $want" >&2
		tail -5 "$tmp/err" >&2
		return 1
	fi
}
has_err() { grep -qF -- "$1" "$tmp/err" || { echo "  stderr lacks '$1':" >&2; cat "$tmp/err" >&2; return 1; }; }
has_out() { grep -qF -- "$1" "$tmp/out" || { echo "  stdout lacks '$1'" >&2; head -3 "$tmp/out" >&2; return 1; }; }
last_err_is() { [ "$(tail -1 "$tmp/err")" = "$1" ] || { echo "  last stderr line: $(tail -1 "$tmp/err")" >&2; return 1; }; }
is_json() { python3 -c 'import json,sys; json.load(open(sys.argv[1]))' "$tmp/out" || { echo "  stdout is not JSON:" >&2; head -5 "$tmp/out" >&2; return 1; }; }

refused=0
commands=(rig demo fit render export convert capture cameras hdr "probe unwrap"
	"probe convert" "probe register" check-rig sessions jobs "queue add"
	"queue cancel" "queue run")
for cmd in "${commands[@]}"; do
	read -r -a words <<<"$cmd"
	check "$cmd --help: exit 0, usage and the common options" bash -c "
		'$glint' ${words[*]} --help >'$tmp/out' 2>'$tmp/err' &&
		grep -Eq '^(usage: |       )glint ${words[0]}' '$tmp/out' &&
		grep -q -- '-q/--quiet' '$tmp/out' && grep -q -- '-v/--verbose' '$tmp/out' &&
		[ ! -s '$tmp/err' ]"
	check "$cmd -v -h: help too" g 0 "${words[@]}" -v -h
	check "$cmd --no-such-flag: exit 2, named, Try ..." eval 'g 2 "${words[@]}" --no-such-flag &&
		has_err "glint $cmd: unknown option '"'"'--no-such-flag'"'"'" &&
		last_err_is "Try '"'"'glint $cmd --help'"'"'."'
	check "$cmd --jsno: did you mean --json" eval 'g 2 "${words[@]}" --jsno && has_err "(did you mean '"'"'--json'"'"'?)"'
	check "$cmd -Z: an unknown short option, exit 2" eval 'g 2 "${words[@]}" -Z && has_err "unknown option '"'"'-Z'"'"'"'
	# The common options are accepted by every command (whatever it then
	# says about its missing arguments).
	for opt in --json -q -v --quiet --verbose; do
		"$glint" "${words[@]}" "$opt" --root "$tmp/nowhere" >"$tmp/out" 2>"$tmp/err" </dev/null
		if grep -q "unknown option '$opt'" "$tmp/err"; then
			echo "  $cmd: $opt refused" >&2
			refused=$((refused + 1))
		fi
	done
done
check "the common options were accepted everywhere" test "$refused" = 0

# Values are checked, with the option and what was expected named.
check "a number out of range" eval 'g 2 fit a b --samples 0 && has_err "glint fit: --samples '"'"'0'"'"': expected an integer in [1, 4096]"'
check "not a number" eval 'g 2 render s.json --paper x --spp many && has_err "--spp '"'"'many'"'"': expected an integer"'
check "a misspelt choice" eval 'g 2 fit a b --optimizer anneel && has_err "(did you mean '"'"'anneal'"'"'?)"'
check "a misspelt model" eval 'g 2 fit a b --model lamberd && has_err "(did you mean '"'"'lambert'"'"'?)"'
check "an ambiguous abbreviation lists its meanings" eval 'g 2 fit a b --s 3 && has_err "option '"'"'--s'"'"' is ambiguous: --samples"'
check "a unique abbreviation is taken (--out for --output)" eval 'g 0 convert "$data/env/venice_sunset_1k.hdr" --out "$tmp/c.pfm" -q && [ -s "$tmp/c.pfm" ]'
check "an option missing its value" eval 'g 2 fit a b --samples && has_err "option '"'"'--samples'"'"' needs a value"'
check "a misspelt command" eval 'g 2 fti && has_err "unknown command '"'"'fti'"'"' (did you mean '"'"'fit'"'"'?)" && last_err_is "Try '"'"'glint --help'"'"'."'
check "a misspelt subcommand" eval 'g 2 queue ad && has_err "(did you mean '"'"'add'"'"'?)"'
check "a misspelt key in a file names it and suggests" bash -c "echo '{\"model\": \"lambert\", \"difuse\": [0.5, 0.5, 0.5]}' >'$tmp/m.json' && ! '$glint' render '$data/demo-scene.json' -m '$tmp/m.json' -o '$tmp/r.exr' 2>'$tmp/err' && grep -q \"unknown key (did you mean 'diffuse'?)\" '$tmp/err'"
check "options after the arguments and '--' ending them" eval 'g 0 convert "$data/env/venice_sunset_1k.hdr" -- "$tmp/d.pfm" && [ -s "$tmp/d.pfm" ]'

# --json: a JSON document on stdout; -q: nothing on stderr.
check "convert --json" eval 'g 0 convert "$data/env/venice_sunset_1k.hdr" "$tmp/e.pfm" --json && is_json'
check "convert -q: silent" eval 'g 0 convert "$data/env/venice_sunset_1k.hdr" "$tmp/f.pfm" -q && [ ! -s "$tmp/err" ] && [ ! -s "$tmp/out" ]'
check "convert without -q says what it did" eval 'g 0 convert "$data/env/venice_sunset_1k.hdr" "$tmp/f1.pfm" && has_err "venice_sunset_1k.hdr ->"'
check "convert -v: debug messages" eval 'g 0 convert "$data/env/venice_sunset_1k.hdr" "$tmp/f2.pfm" -v && has_err "glint: debug: read " && has_err "1024x512"'
check "convert --json -v: debug messages as JSON lines" eval 'g 0 convert "$data/env/venice_sunset_1k.hdr" "$tmp/f3.pfm" --json -v && grep -q "\"level\": *\"debug\"" "$tmp/err"'
check "cameras --json" eval 'g 0 cameras --json && is_json'
check "jobs --json" eval 'g 0 jobs --json --root "$tmp" && is_json'
check "sessions --json" eval 'g 0 sessions --json --root "$tmp" && is_json'
check "check-rig --json" eval 'g 0 check-rig --json --config "$data/rig-sim.json" && is_json'
check "a failure under --json: the error as a JSON line" eval 'g 1 convert "$tmp/missing.exr" "$tmp/g.pfm" --json && python3 -c "import json,sys; d=json.loads(open(sys.argv[1]).read().splitlines()[-1]); sys.exit(d[\"level\"] != \"error\")" "$tmp/err"'
check "JSON log lines carry an RFC 3339 UTC time" eval 'g 1 convert "$tmp/missing.exr" "$tmp/g.pfm" --json && python3 -c "
import json, re, sys
for line in open(sys.argv[1]).read().splitlines():
    d = json.loads(line)
    assert re.fullmatch(r\"\\d{4}-\\d\\d-\\d\\dT\\d\\d:\\d\\d:\\d\\d\\.\\d{3}Z\", d[\"time\"]), d
" "$tmp/err"'

# Under systemd, stderr is the journal: JOURNAL_STREAM names it by
# device:inode, and each line carries its syslog priority for journald.
journal() { # stderr file, then glint's arguments
	local f=$1
	shift
	: >"$f"
	JOURNAL_STREAM=$(stat -c '%d:%i' "$f") "$glint" "$@" 2>>"$f" >/dev/null </dev/null
}
check "journal: an error line starts with <3>" eval 'journal "$tmp/j1" convert "$tmp/missing.exr" "$tmp/g.pfm"; head -1 "$tmp/j1" | grep -q "^<3>glint: error: "'
check "journal: an info line with <6>, a debug line with <7>" eval 'journal "$tmp/j2" convert "$data/env/venice_sunset_1k.hdr" "$tmp/f4.pfm" -v && grep -q "^<6>glint: .*venice_sunset_1k.hdr ->" "$tmp/j2" && grep -q "^<7>glint: debug: " "$tmp/j2"'
check "journal: JSON lines too" eval 'journal "$tmp/j3" convert "$tmp/missing.exr" "$tmp/g.pfm" --json; grep -q "^<3>{" "$tmp/j3"'
check "another stream named: no prefix" eval ': >"$tmp/j4"; JOURNAL_STREAM=$(stat -c "%d:%i" "$tmp/j1") "$glint" convert "$tmp/missing.exr" "$tmp/g.pfm" 2>"$tmp/j4"; head -1 "$tmp/j4" | grep -q "^glint: error: "'

echo "$((checks - fails)) passed, $fails failed"
[ "$fails" = 0 ]
