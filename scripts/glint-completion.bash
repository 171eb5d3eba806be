# bash completion for glint: the commands from `glint --help`, a command's
# options from `glint COMMAND --help`, files elsewhere.  Installed to
# share/bash-completion/completions/glint (from scripts/glint-completion.bash).
_glint()
{
	local cur prev words cword
	cur=${COMP_WORDS[COMP_CWORD]}
	local glint=${COMP_WORDS[0]}
	if ((COMP_CWORD == 1)); then
		local cmds
		cmds=$("$glint" --help 2>/dev/null |
			sed -n '/^commands:/,/^$/s/^  \([a-z][a-z-]*\) .*/\1/p')
		mapfile -t COMPREPLY < <(compgen -W "$cmds --help" -- "$cur")
		return
	fi
	if [[ $cur == -* ]]; then
		local opts
		opts=$("$glint" "${COMP_WORDS[1]}" --help 2>/dev/null |
			grep -o -- '--[a-z][a-z0-9-]*' | sort -u)
		mapfile -t COMPREPLY < <(compgen -W "$opts" -- "$cur")
		return
	fi
	mapfile -t COMPREPLY < <(compgen -f -- "$cur")
}
complete -o filenames -F _glint glint
