# Shell tests' synchronisation: wait on a state with a deadline, never a
# fixed sleep.  Source it: . "$(dirname "$0")/../wait.sh"
#
# wait_until SECONDS COMMAND...: run COMMAND every 50 ms until it succeeds
# (0) or SECONDS pass (1, saying what was waited for).
wait_until() {
	local deadline=$((SECONDS + $1))
	shift
	until "$@" >/dev/null 2>&1; do
		if ((SECONDS >= deadline)); then
			echo "timed out waiting for: $*" >&2
			return 1
		fi
		sleep 0.05
	done
}

# exists GLOB: some file matches
exists() {
	compgen -G "$1" >/dev/null
}
