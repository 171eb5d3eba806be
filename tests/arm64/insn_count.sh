#!/usr/bin/env bash
# bench/qemu_insn_count.c counts what a program retires: a loop of
# exactly two instructions (subs, b.ne; inline assembly, so the compiler
# cannot change it) run 1,000,000 and 2,000,000 times must differ by
# exactly 2,000,000 instructions (the rest of the program is the same:
# its argument has as many digits).
#   tests/arm64/insn_count.sh PLUGIN.so
set -euo pipefail
plugin=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cat >"$tmp/loop.c" <<'C'
#include <stdlib.h>
int main(int argc, char **argv)
{
	long n = argc > 1 ? atol(argv[1]) : 1;
	__asm__ volatile("1: subs %0, %0, #1\n\tb.ne 1b" : "+r"(n) : : "cc");
	return (int)n;
}
C
aarch64-linux-gnu-gcc -O2 -static -o "$tmp/loop" "$tmp/loop.c"
count() {
	qemu-aarch64 -plugin "$plugin" -d plugin -D "$tmp/log" "$tmp/loop" "$1"
	sed -n 's/^instructions //p' "$tmp/log"
}
a=$(count 1000000)
b=$(count 2000000)
echo "insn_count: $a and $b instructions, difference $((b - a)) (expected 2000000)"
[ $((b - a)) = 2000000 ]
