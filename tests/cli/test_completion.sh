#!/usr/bin/env bash
# The bash completion (scripts/glint-completion.bash): commands from
# glint's own --help, a command's subcommands and options from its --help
# (a subcommand's options from the subcommand's), files otherwise.
#   test_completion.sh GLINT COMPLETION
set -u
glint=$1
. "$2"
fail=0
complete_at() { # words... -> COMPREPLY for the last word
	COMP_WORDS=("$glint" "${@}")
	COMP_CWORD=$#
	COMPREPLY=()
	_glint
	printf '%s\n' "${COMPREPLY[@]}"
}
expect() { # what, got, wanted word
	if grep -qx -- "$3" <<<"$2"; then
		echo "ok   $1"
	else
		echo "FAIL $1: got [$(tr '\n' ' ' <<<"$2")], wanted $3"
		fail=1
	fi
}
expect "commands" "$(complete_at fi)" fit
expect "every command" "$(complete_at '')" check-rig
expect "an option of fit" "$(complete_at fit --mod)" --model
expect "an option of rig" "$(complete_at rig --on)" --once
got=$(complete_at fit --mod)
if grep -qx -- --once <<<"$got"; then
	echo "FAIL fit offered rig's --once"
	fail=1
fi
expect "a subcommand of probe" "$(complete_at probe un)" unwrap
expect "a subcommand of queue" "$(complete_at queue ca)" cancel
expect "an option of probe unwrap" "$(complete_at probe unwrap --foc)" --focal-px
got=$(complete_at probe convert --)
if grep -qx -- --focal-px <<<"$got"; then
	echo "FAIL probe convert offered unwrap's --focal-px"
	fail=1
fi
tmp=$(mktemp -d)
touch "$tmp/photo.exr"
expect "files" "$(complete_at fit "$tmp/pho")" "$tmp/photo.exr"
rm -rf "$tmp"
exit $fail
