/* SPDX-License-Identifier: MIT */
#define _POSIX_C_SOURCE 200809L
#include "suggest.h"

#include <stdio.h>
#include <string.h>

/* Edit distance of the first 63 bytes of a and b, a swap of two
 * neighbours counting as one edit (optimal string alignment). */
static int distance(const char *a, const char *b)
{
	int la = (int)strnlen(a, 63), lb = (int)strnlen(b, 63);
	static _Thread_local int d[64][64];

	for (int i = 0; i <= la; i++)
		d[i][0] = i;
	for (int j = 0; j <= lb; j++)
		d[0][j] = j;
	for (int i = 1; i <= la; i++)
		for (int j = 1; j <= lb; j++) {
			int best = d[i - 1][j - 1] + (a[i - 1] != b[j - 1]);
			if (d[i - 1][j] + 1 < best)
				best = d[i - 1][j] + 1;
			if (d[i][j - 1] + 1 < best)
				best = d[i][j - 1] + 1;
			if (i > 1 && j > 1 && a[i - 1] == b[j - 2] &&
			    a[i - 2] == b[j - 1] && d[i - 2][j - 2] + 1 < best)
				best = d[i - 2][j - 2] + 1;
			d[i][j] = best;
		}
	return d[la][lb];
}

const char *glint_suggest(const char *word, const char *const *candidates)
{
	const char *best = NULL;
	int bd = 1 << 30, len = (int)strlen(word);

	for (int i = 0; candidates && candidates[i]; i++) {
		int d = distance(word, candidates[i]);
		if (d < bd) {
			bd = d;
			best = candidates[i];
		}
	}
	/* A third of the word, at least one edit: "smaples" -> "samples",
	 * never "x" -> "json". */
	int limit = len / 3 > 1 ? len / 3 : 1;
	return best && bd <= limit && bd < len ? best : NULL;
}

const char *glint_suggest_hint(const char *word, const char *const *candidates)
{
	static _Thread_local char hint[96];
	const char *near = glint_suggest(word, candidates);

	if (!near)
		return "";
	snprintf(hint, sizeof(hint), " (did you mean '%.60s'?)", near);
	return hint;
}
