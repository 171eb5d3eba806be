#!/usr/bin/env bash
# meson install into a DESTDIR, then the installed glint run from outside
# the source and build trees: its help, check-rig on the installed sim rig
# and the demo, with its data found in the installed datadir only (beside
# the binary, as installed under the DESTDIR), and the rig commands'
# default rig file the installed sysconfdir's rig.json.
#   test_install.sh BUILD_DIR PREFIX DATADIR SYSCONFDIR MANDIR
set -uo pipefail
build=$1 prefix=$2 datadir=$3 sysconfdir=$4 mandir=$5
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
check() { # name command...
	local name=$1
	shift
	if "$@" >"$tmp/out" 2>&1; then
		echo "ok   $name"
	else
		echo "FAIL $name"
		sed 's/^/     /' "$tmp/out" | tail -20
		fail=1
	fi
}

dest=$tmp/dest
meson install -C "$build" --destdir "$dest" --no-rebuild --quiet >"$tmp/install.log" 2>&1 ||
	{ cat "$tmp/install.log"; exit 1; }
bin=$dest$prefix/bin/glint
data=$dest$prefix/$datadir/glint
check "binary installed" test -x "$bin"
check "shell completions installed where bash-completion and zsh look" \
	test -f "$dest$prefix/$datadir/bash-completion/completions/glint" -a -f "$dest$prefix/$datadir/zsh/vendor-completions/_glint"
check "data installed" test -f "$data/paper-table1.json" -a -f "$data/env/venice_sunset_1k.hdr" -a -f "$data/rig-sim.json"
check "systemd unit installed, pointing at the installed binary" \
	grep -q "^ExecStart=$prefix/bin/glint rig --config $sysconfdir/glint/rig.json" "$dest$prefix/lib/systemd/system/glint-rig.service"
# No udev rule for every camera and GPIO chip: check-rig --udev-rules
# writes one for the rig's own devices (the vm-udev test).
check "no catch-all udev rule installed" test ! -e "$dest$prefix/lib/udev/rules.d/70-glint.rules"
# The unit's sandbox: systemd's own reading of it (no unknown or
# malformed line; verify needs the binary it names, so a copy names the
# installed one) and its exposure at 3.0 or below (--threshold is in
# tenths).
unit=$dest$prefix/lib/systemd/system/glint-rig.service
sandbox() {
	command -v systemd-analyze >/dev/null || { echo "systemd-analyze is not installed"; return 1; }
	mkdir -p "$tmp/unit"
	sed "s#^ExecStart=$prefix/bin/glint#ExecStart=$bin#" "$unit" >"$tmp/unit/glint-rig.service"
	local out
	out=$(systemd-analyze verify "$tmp/unit/glint-rig.service" 2>&1)
	[ -z "$out" ] || { echo "systemd-analyze verify: $out"; return 1; }
	systemd-analyze security --offline=true --threshold=30 "$tmp/unit/glint-rig.service" |
		tail -1
}
check "systemd unit: verified, exposure at most 3.0" sandbox
check "example rig file installed" test -f "$dest$sysconfdir/glint/rig.example.json"
check "docs installed" test -f "$dest$prefix/$datadir/doc/glint/rig.md"
# Man pages: glint(1) and one per command of glint --help's table, each
# rendering with its NAME line and the command's own options.
man1=$dest$prefix/$mandir/man1
manpages() {
	command -v help2man >/dev/null || { echo "help2man is not installed (scripts/setup installs it)"; return 1; }
	grep -q '^glint \\- measure a material' "$man1/glint.1" || return 1
	local c n=0
	for c in $("$bin" --help | awk '/^commands:/ {t = 1; next} t && /^  [a-z]/ {print $1}'); do
		[ -f "$man1/glint-$c.1" ] || { echo "no man page for $c"; return 1; }
		grep -q "^glint-$c \\\\- " "$man1/glint-$c.1" ||
			{ echo "glint-$c.1 has no NAME line"; return 1; }
		n=$((n + 1))
	done
	# A page per subcommand of a command whose help has a table of them
	# (probe, queue), with the subcommand's own options.
	local s subs=0
	for c in $("$bin" --help | awk '/^commands:/ {t = 1; next} t && /^  [a-z]/ {print $1}'); do
		for s in $("$bin" "$c" --help | awk '/^subcommands/ {t = 1; next} t && /^  [a-z]/ {print $1} t && /^$/ {exit}'); do
			[ -f "$man1/glint-$c-$s.1" ] || { echo "no man page for $c $s"; return 1; }
			grep -q "^glint-$c-$s \\\\- " "$man1/glint-$c-$s.1" ||
				{ echo "glint-$c-$s.1 has no NAME line"; return 1; }
			subs=$((subs + 1))
		done
	done
	[ "$subs" -ge 6 ] || { echo "$subs subcommand pages, expected probe's 3 and queue's 3"; return 1; }
	grep -q -- '--focal-px' "$man1/glint-probe-unwrap.1" && ! grep -q -- '--focal-px' "$man1/glint-probe-convert.1" ||
		{ echo "glint-probe-unwrap.1 and glint-probe-convert.1 do not hold their own options"; return 1; }
	grep -q 'material.gltf' "$man1/glint-fit.1" || return 1
	# Rendered by man where it is installed: no roff warnings.
	if command -v man >/dev/null; then
		MANWIDTH=100 man --warnings -l "$man1/glint-fit.1" 2>&1 >/dev/null | grep . && return 1
		MANWIDTH=100 man -l "$man1/glint-fit.1" | grep -q "glint-fit - recover" || return 1
		# Each form of a command's usage is a SYNOPSIS line of its own
		# (help2man ran them together into the description).
		local forms lines
		for c in $("$bin" --help | awk '/^commands:/ {t = 1; next} t && /^  [a-z]/ {print $1}'); do
			forms=$("$bin" "$c" --help | sed -n '1,/^$/p' | grep -c -E '^(usage: |       )glint ')
			lines=$(MANWIDTH=200 man -l "$man1/glint-$c.1" | sed -n '/^SYNOPSIS/,/^DESCRIPTION/p' | grep -c '^       glint ')
			[ "$forms" -ge 1 ] && [ "$forms" = "$lines" ] ||
				{ echo "glint-$c.1: $lines SYNOPSIS lines for $forms usage forms"; return 1; }
		done
	fi
	# Each command its own page (jobs, sessions and queue shared one).
	local a b
	for a in jobs sessions queue; do
		for b in jobs sessions queue; do
			[ "$a" = "$b" ] && continue
			grep -v '^\.TH\|glint-' "$man1/glint-$a.1" >"$tmp/ma" 2>/dev/null
			grep -v '^\.TH\|glint-' "$man1/glint-$b.1" >"$tmp/mb" 2>/dev/null
			cmp -s "$tmp/ma" "$tmp/mb" && { echo "glint-$a.1 and glint-$b.1 say the same"; return 1; }
		done
	done
	echo "$n command pages"
	[ "$n" -ge 14 ]
}
check "man pages installed: glint(1) and one per command" manpages

cd "$tmp" || exit 1
unset GLINT_DATA_DIR
# The installed binary finds its data beside itself (the datadir under the
# root it was installed to), never the source tree's.
check "installed demo without GLINT_DATA_DIR: its data found beside the binary" \
	bash -c "'$bin' demo --material yellow-plastic -o '$tmp/d0' --json -q >'$tmp/d0.json' && grep -q '\"scene\": \"$data/demo-scene.json\"' '$tmp/d0.json'"
check "... and wrote its fit" test -f "$tmp/d0/fit/params.json"
# The rig commands without --config take the installed appliance's rig
# file: missing, named with what to do; present, used.
conf=$dest$sysconfdir/glint
check "installed check-rig without a rig.json: refused, naming it and the example" \
	bash -c "! '$bin' check-rig >'$tmp/cr.log' 2>&1 && grep -q 'no rig file at $conf/rig.json' '$tmp/cr.log' && grep -q 'rig.example.json' '$tmp/cr.log'"
sed -e "s|\"output\": \"captures\"|\"output\": \"$tmp/var/captures\"|" \
	-e "s|\"scenario\": \"sim-press.json\"|\"scenario\": \"$data/sim-press.json\"|" \
	"$data/rig-sim.json" >"$conf/rig.json"
mkdir -p "$tmp/var/captures"
chmod 755 "$tmp"
# As the service user would run it (a user of its own, not root).
as_user=()
if [ "$(id -u)" = 0 ] && command -v setpriv >/dev/null; then
	as_user=(setpriv --reuid=nobody --regid=nogroup --clear-groups)
	chown nobody "$tmp/var/captures"
fi
check "installed check-rig with the installed rig.json, no --config${as_user:+, as nobody}" \
	"${as_user[@]}" "$bin" check-rig
check "installed jobs: the installed rig file's captures folder" \
	bash -c "'$bin' jobs --json | grep -q '$tmp/var/captures'"
export GLINT_DATA_DIR=$data
check "installed glint --help" "$bin" --help
check "installed check-rig on the installed sim rig" "$bin" check-rig --config "$data/rig-sim.json"
exit $fail
