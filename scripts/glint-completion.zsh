#compdef glint
# zsh completion for glint, by the bash completion's rules
# (scripts/glint-completion.bash): the commands from `glint --help` (with
# their one-line descriptions), a command's subcommands from the table of
# them in `glint COMMAND --help` (probe, queue), its options from
# `glint COMMAND [SUB] --help`, files elsewhere.  Installed as
# share/zsh/vendor-completions/_glint (from scripts/glint-completion.zsh).

# _glint_table HELP_ARGS... : the "name:description" lines of the table
# that follows a line starting "commands:" or "subcommands" in that help.
_glint_table() {
	"$@" --help 2>/dev/null |
		sed -n '/^\(sub\)*commands/,/^$/s/^  \([a-z][a-z-]*\)  *\(.*\)$/\1:\2/p'
}

_glint() {
	local glint=${words[1]}
	local -a cmds subs opts
	if (( CURRENT == 2 )); then
		cmds=(${(f)"$(_glint_table $glint)"})
		_describe -t commands 'glint command' cmds
		return
	fi
	subs=(${(f)"$(_glint_table $glint ${words[2]})"})
	if (( CURRENT == 3 && ${#subs} )) && [[ $PREFIX != -* ]]; then
		_describe -t subcommands "glint ${words[2]} subcommand" subs
		return
	fi
	if [[ $PREFIX == -* ]]; then
		local -a sub
		if (( ${#subs} && ${subs[(I)${words[3]}:*]} )); then
			sub=(${words[3]})
		fi
		opts=(${(u)${(f)"$($glint ${words[2]} $sub --help 2>/dev/null |
			grep -o -- '--[a-z][a-z0-9-]*')"}})
		compadd -a opts
		return
	fi
	_files
}

_glint "$@"
