# Shell tests' synchronisation: wait on a state with a deadline, never a
# fixed sleep.  Source it: . "$(dirname "$0")/../wait.sh"
#
# Deadlines are seconds on the reference machine, scaled by how slow this
# one is (scripts/machine-speed, percent, at least 100; GLINT_SLOWNESS
# when set): measured only when a wait outlasts its unscaled deadline, so
# a wait that ends in time costs no measurement.

_glint_slowness() {
	if [ -z "${GLINT_SLOWNESS:-}" ]; then
		local here
		here=$(dirname "${BASH_SOURCE[0]}")
		GLINT_SLOWNESS=$(python3 "$here/../scripts/machine-speed" 2>/dev/null) ||
			GLINT_SLOWNESS=100
		export GLINT_SLOWNESS
	fi
	echo "$GLINT_SLOWNESS"
}

# scaled SECONDS: SECONDS on this machine (whole seconds, rounded up)
scaled() {
	local s
	s=$(_glint_slowness)
	echo $((($1 * s + 99) / 100))
}

# wait_until SECONDS COMMAND...: run COMMAND every 50 ms until it succeeds
# (0) or SECONDS (scaled) pass (1, saying what was waited for).
wait_until() {
	local start=$SECONDS limit=$1 scaled_once=0
	shift
	until "$@" >/dev/null 2>&1; do
		if ((SECONDS - start >= limit)); then
			if ((!scaled_once)); then
				scaled_once=1
				limit=$(scaled "$limit")
				continue
			fi
			echo "timed out waiting for: $* ($limit s)" >&2
			return 1
		fi
		sleep 0.05
	done
}

# exists GLOB: some file matches
exists() {
	compgen -G "$1" >/dev/null
}
