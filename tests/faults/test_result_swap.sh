#!/usr/bin/env bash
# The result swap under SIGKILL: strace kills the writer at the
# k-th call of each of rename, renameat2, unlink, unlinkat, rmdir, fsync,
# fdatasync and mkdir in turn.  After every kill the folder must hold a
# whole result, the old one or the new one, never none and never a mix;
# after the next start's sweep it still does and no leftovers remain.
#   test_result_swap.sh SWAP_WRITER
set -euo pipefail
writer=$1
command -v strace >/dev/null || {
	echo "strace not installed: skipped" >&2
	exit 77
}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
out=$tmp/result

whole() { # prints the tag the result holds, or fails
	local a b c
	a=$(cat "$out/a.txt") && b=$(cat "$out/b.txt") && c=$(cat "$out/c.txt") ||
		return 1
	# the three files and the manifest naming them (core/atomic_dir.h)
	[ "$a" = "$b" ] && [ "$b" = "$c" ] &&
		[ "$(ls "$out" | grep -vx glint-outputs.txt | wc -l)" = 3 ] &&
		[ "$(sort "$out/glint-outputs.txt" | tr '\n' ' ')" = "a.txt b.txt c.txt " ] ||
		return 1
	echo "$a"
}

kills=0
for call in rename renameat2 unlink unlinkat rmdir fsync fdatasync mkdir; do
	for k in $(seq 1 12); do
		rm -rf "$tmp"/result*
		"$writer" "$out" old
		set +e
		(strace -f -qq -o /dev/null \
			-e trace="$call" -e inject="$call":signal=KILL:when="$k" \
			"$writer" "$out" new) 2>/dev/null
		rc=$?
		set -e
		if [ "$rc" = 0 ]; then
			[ "$(whole)" = new ] || {
				echo "FAIL: $call #$k: writer succeeded, result not new" >&2
				exit 1
			}
			break # fewer than k calls: this syscall is done
		fi
		kills=$((kills + 1))
		tag=$(whole) || {
			echo "FAIL: killed at $call #$k: no whole result:" >&2
			ls -la "$tmp" "$out" >&2 || true
			exit 1
		}
		case $tag in old | new) ;; *)
			echo "FAIL: $call #$k: result says '$tag'" >&2
			exit 1
			;;
		esac
		"$writer" --sweep "$out" >/dev/null
		[ "$(whole)" = "$tag" ] || {
			echo "FAIL: $call #$k: the sweep changed the result" >&2
			exit 1
		}
		left=$(cd "$tmp" && ls -d result.* 2>/dev/null || true)
		[ -z "$left" ] || {
			echo "FAIL: $call #$k: leftovers after the sweep: $left" >&2
			exit 1
		}
		echo "killed at $call #$k: $tag, whole"
	done
done
# The kills above must have reached the swap itself.
[ "$kills" -ge 5 ] || {
	echo "FAIL: only $kills kills: the injection did not reach the swap" >&2
	exit 1
}
echo "ok: $kills kills, a whole result after each"
