#!/usr/bin/env bash
# The bash and zsh completions (scripts/glint-completion.bash, .zsh):
# commands from glint's own --help, a command's subcommands and options
# from its --help (a subcommand's options from the subcommand's), files
# otherwise.
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

# zsh (scripts/glint-completion.zsh, autoloaded as _glint): the same
# cases, the completion system's _describe, compadd and _files stood in
# for by functions that print the candidates they are given.
zsh_file=${2%.bash}.zsh
if command -v zsh >/dev/null; then
	mkdir "$tmp/fpath"
	cp "$zsh_file" "$tmp/fpath/_glint"
	zsh_at() {
		zsh -f -c '
			_describe() { local a=${@[-1]}; print -l -- ${${(P)a}%%:*} }
			compadd() { print -l -- ${(P)2} }
			_files() { print -- "(files)" }
			fpath=($1 $fpath); autoload -Uz _glint
			shift; words=("$@"); CURRENT=$#words; PREFIX=${words[-1]}
			_glint' zsh "$tmp/fpath" "$glint" "$@"
	}
	expect "zsh: commands" "$(zsh_at fi)" fit
	expect "zsh: every command" "$(zsh_at '')" check-rig
	expect "zsh: an option of fit" "$(zsh_at fit --mod)" --model
	expect "zsh: a subcommand of probe" "$(zsh_at probe un)" unwrap
	expect "zsh: an option of probe unwrap" "$(zsh_at probe unwrap --foc)" --focal-px
	if grep -qx -- --focal-px <<<"$(zsh_at probe convert --)"; then
		echo "FAIL zsh: probe convert offered unwrap's --focal-px"
		fail=1
	fi
	expect "zsh: files elsewhere" "$(zsh_at fit x)" "(files)"
else
	echo "FAIL zsh is not installed (scripts/setup installs it)"
	fail=1
fi
rm -rf "$tmp"
exit $fail
