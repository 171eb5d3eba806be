/* SPDX-License-Identifier: MIT */
#ifndef GLINT_FIT_REPORT_H
#define GLINT_FIT_REPORT_H

/*
 * A fit's report.html: one page that opens in a browser from the result
 * folder without a server (its pictures are the folder's compare PNGs, by
 * relative links): the material's name, whether the fit is accepted and
 * why, photo | render | error with the residual plots for each photo,
 * the parameter table with standard errors and intervals (a parameter
 * the photo does not determine said so), the misfit's verdict, the
 * uncertainty's method, the inputs and the exports.  Built from the
 * fit's params.json document alone.
 *
 * Errors: NULL when out of memory.  Threads: re-entrant.  Who frees: the
 * text, with free().
 */

#include <jansson.h>

/* The page for params.json document doc, nviews photos (compare.png,
 * compare-2.png, ...). */
char *glint_fit_report_html(const json_t *doc, int nviews);

#endif
