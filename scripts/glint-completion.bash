# bash completion for glint: the commands from `glint --help`, a command's
# subcommands from the table of them in `glint COMMAND --help` (probe,
# queue), its options from `glint COMMAND [SUB] --help`, files elsewhere.
# Installed to share/bash-completion/completions/glint (from
# scripts/glint-completion.bash).
_glint_subcommands() # COMMAND: the subcommands its help lists
{
	"$1" "$2" --help 2>/dev/null |
		sed -n '/^subcommands/,/^$/s/^  \([a-z][a-z-]*\) .*/\1/p'
}
_glint()
{
	local cur
	cur=${COMP_WORDS[COMP_CWORD]}
	local glint=${COMP_WORDS[0]}
	if ((COMP_CWORD == 1)); then
		local cmds
		cmds=$("$glint" --help 2>/dev/null |
			sed -n '/^commands:/,/^$/s/^  \([a-z][a-z-]*\) .*/\1/p')
		mapfile -t COMPREPLY < <(compgen -W "$cmds --help" -- "$cur")
		return
	fi
	local subs
	subs=$(_glint_subcommands "$glint" "${COMP_WORDS[1]}")
	if ((COMP_CWORD == 2)) && [ -n "$subs" ] && [[ $cur != -* ]]; then
		mapfile -t COMPREPLY < <(compgen -W "$subs" -- "$cur")
		return
	fi
	if [[ $cur == -* ]]; then
		local opts sub=
		if [ -n "$subs" ] && grep -qx -- "${COMP_WORDS[2]}" <<<"$subs"; then
			sub=${COMP_WORDS[2]}
		fi
		opts=$("$glint" "${COMP_WORDS[1]}" $sub --help 2>/dev/null |
			grep -o -- '--[a-z][a-z0-9-]*' | sort -u)
		mapfile -t COMPREPLY < <(compgen -W "$opts" -- "$cur")
		return
	fi
	mapfile -t COMPREPLY < <(compgen -f -- "$cur")
}
complete -o filenames -F _glint glint
