/* SPDX-License-Identifier: MIT */
#ifndef GLINT_TESTS_FUZZ_H
#define GLINT_TESTS_FUZZ_H

/*
 * Fuzz harnesses of every reader of outside input.  Each fuzz_*.c defines
 * LLVMFuzzerTestOneInput; built with -Dfuzz=true (clang) it links
 * libFuzzer, otherwise replay.c's main() runs it on the files and folders
 * it is given (the corpus and the regression inputs), so every build
 * replays them.
 */

#include <stddef.h>
#include <stdint.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerInitialize(int *argc, char ***argv);

/* The input as a file the readers can open by path: a memfd, named
 * /proc/self/fd/N (no extension), rewritten for each input. */
const char *fuzz_path(const uint8_t *data, size_t size);

/* The same as a regular file named input.EXT in a private folder (made
 * once, removed at exit), for readers that choose by the extension. */
const char *fuzz_path_ext(const uint8_t *data, size_t size, const char *ext);

#endif
