/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CORE_SUGGEST_H
#define GLINT_CORE_SUGGEST_H

/* The candidate (of a NULL-terminated list) closest to `word` by edit
 * distance, when close enough to be a likely misspelling; NULL
 * otherwise.  For "did you mean" in errors about names.
 *
 * Errors: none.  Threads: re-entrant (the hint is the caller's buffer or
 * static text).  Who frees: nothing.
 */
const char *glint_suggest(const char *word, const char *const *candidates);

/* The same as text for an error message: " (did you mean 'NAME'?)", or ""
 * when nothing is close.  Valid until the thread's next call. */
const char *glint_suggest_hint(const char *word, const char *const *candidates);

#endif
