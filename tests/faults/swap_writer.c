/* SPDX-License-Identifier: MIT */
/*
 * The result swap under test: `swap_writer DIR TAG` writes a result folder
 * DIR holding three files that all say TAG (through glint_atomic_dir, as
 * `glint fit` writes its results); `swap_writer --sweep DIR` cleans up as
 * the next start does.  test_result_swap.sh kills it at every rename,
 * unlink, rmdir and fsync and checks what is left.
 */
#include "core/atomic_dir.h"
#include "core/atomic_file.h"
#include "core/error.h"

#include <stdio.h>
#include <string.h>

int main(int argc, char **argv)
{
	static const char *const names[] = { "a.txt", "b.txt", "c.txt" };
	struct glint_atomic_dir ad;
	char path[4200];

	if (argc == 3 && !strcmp(argv[1], "--sweep")) {
		printf("%d\n", glint_atomic_dir_sweep(argv[2]));
		return 0;
	}
	if (argc != 3) {
		fprintf(stderr, "usage: swap_writer DIR TAG | --sweep DIR\n");
		return 2;
	}
	if (glint_atomic_dir_open(&ad, argv[1]) < 0)
		goto err;
	for (int i = 0; i < 3; i++) {
		const char *p = glint_atomic_dir_file(&ad, names[i], path,
						      sizeof(path));
		if (glint_atomic_write_file(p, argv[2], strlen(argv[2])) < 0) {
			glint_atomic_dir_abort(&ad);
			goto err;
		}
	}
	if (glint_atomic_dir_commit(&ad) < 0)
		goto err;
	return 0;
err:
	fprintf(stderr, "swap_writer: %s\n", glint_error_msg());
	return 1;
}
