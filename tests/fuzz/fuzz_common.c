/* SPDX-License-Identifier: MIT */
#define _GNU_SOURCE /* memfd_create, mkdtemp */
#include "fuzz.h"

#include "core/log.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
	(void)argc;
	(void)argv;
	/* Keep every input under libFuzzer's memory limit: the readers'
	 * size policy, at 4 M pixels (48 MB as floats). */
	setenv("GLINT_MAX_PIXELS", "4194304", 1);
	glint_log_set_mode(GLINT_LOG_QUIET);
	return 0;
}

const char *fuzz_path(const uint8_t *data, size_t size)
{
	static int fd = -1;
	static char path[64];

	if (fd < 0) {
		fd = memfd_create("glint-fuzz", 0);
		if (fd < 0) {
			perror("memfd_create");
			abort();
		}
		snprintf(path, sizeof(path), "/proc/self/fd/%d", fd);
	}
	if (ftruncate(fd, 0) < 0 ||
	    (size && pwrite(fd, data, size, 0) != (ssize_t)size)) {
		perror("fuzz input");
		abort();
	}
	return path;
}

static char ext_dir[64], ext_file[96];

static void remove_ext_file(void)
{
	unlink(ext_file);
	rmdir(ext_dir);
}

const char *fuzz_path_ext(const uint8_t *data, size_t size, const char *ext)
{
	if (!ext_dir[0]) {
		snprintf(ext_dir, sizeof(ext_dir), "%s",
			 "/tmp/glint-fuzz-ext.XXXXXX");
		if (!mkdtemp(ext_dir)) {
			perror("mkdtemp");
			abort();
		}
		atexit(remove_ext_file);
	}
	if (ext_file[0])
		unlink(ext_file);
	snprintf(ext_file, sizeof(ext_file), "%s/input.%s", ext_dir, ext);
	FILE *f = fopen(ext_file, "wb");
	if (!f || (size && fwrite(data, 1, size, f) != size) || fclose(f)) {
		perror(ext_file);
		abort();
	}
	return ext_file;
}
