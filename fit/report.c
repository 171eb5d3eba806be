/* SPDX-License-Identifier: MIT */
/* A fit's report.html (report.h). */
#define _GNU_SOURCE /* open_memstream */
#include "report.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* s with &, <, > and " escaped. */
static void esc(FILE *f, const char *s)
{
	for (; s && *s; s++)
		switch (*s) {
		case '&':
			fputs("&amp;", f);
			break;
		case '<':
			fputs("&lt;", f);
			break;
		case '>':
			fputs("&gt;", f);
			break;
		case '"':
			fputs("&quot;", f);
			break;
		default:
			fputc(*s, f);
		}
}

static const char *str(const json_t *o, const char *key)
{
	const char *s = json_string_value(json_object_get(o, key));
	return s ? s : "";
}

static double num(const json_t *o, const char *key)
{
	const json_t *v = json_object_get(o, key);
	return json_is_number(v) ? json_number_value(v) : NAN;
}

static void param_rows(FILE *f, const json_t *params)
{
	size_t k;
	const json_t *p;
	json_array_foreach(params, k, p)
	{
		const json_t *iv = json_object_get(p, "interval");
		double lo = json_number_value(json_array_get(iv, 0));
		double hi = json_number_value(json_array_get(iv, 1));
		int det = !json_is_false(json_object_get(p, "determined"));
		fputs("<tr><td>", f);
		esc(f, str(p, "name"));
		fprintf(f, "</td><td>%.4f</td><td>%.4f</td>", num(p, "value"),
			num(p, "stderr"));
		if (json_is_array(iv))
			fprintf(f, "<td>[%.4f, %.4f]</td>", lo, hi);
		else
			fputs("<td>&mdash;</td>", f);
		fprintf(f, "<td>%s%s</td></tr>\n",
			det ? "" : "<b>not determined by the photo</b>",
			json_is_true(json_object_get(p, "at_bound"))
				? (det ? "at its bound" : ", at its bound")
				: "");
	}
}

static void views(FILE *f, int nviews)
{
	for (int k = 0; k < nviews; k++) {
		char name[32];
		if (k)
			snprintf(name, sizeof(name), "compare-%d.png", k + 1);
		else
			snprintf(name, sizeof(name), "compare.png");
		fprintf(f,
			"<figure><img src=\"%s\" alt=\"photo %d: photo, "
			"render, render - photo, residual by angle\" "
			"onerror=\"this.replaceWith('%s is missing from this "
			"folder')\">"
			"<figcaption>Photo %d: the photo, the fitted "
			"material's render, their difference (render - "
			"photo, luminance), and the residual by angle from "
			"the view and from the mirror direction of the "
			"brightest light (mean &plusmn; 2 standard errors; "
			"red beyond 5).</figcaption></figure>\n",
			name, k + 1, name, k + 1);
	}
}

char *glint_fit_report_html(const json_t *doc, int nviews)
{
	char *text = NULL;
	size_t len = 0;
	FILE *f = open_memstream(&text, &len);
	if (!f)
		return NULL;
	const json_t *mat = json_object_get(doc, "material");
	const json_t *acc = json_object_get(doc, "acceptance");
	const json_t *unc = json_object_get(doc, "uncertainty");
	const json_t *in = json_object_get(doc, "inputs");
	const char *name = str(mat, "name");
	int accepted = json_is_true(json_object_get(doc, "accepted"));
	double level = num(unc, "level");

	fputs("<!DOCTYPE html>\n<html lang=\"en\"><head><meta "
	      "charset=\"utf-8\"><title>glint fit: ",
	      f);
	esc(f, *name ? name : "material");
	fputs("</title><style>body{font-family:sans-serif;max-width:70em;"
	      "margin:1em auto;padding:0 1em;color:#222}"
	      "table{border-collapse:collapse}"
	      "td,th{padding:.2em .8em;border-bottom:1px solid #ddd;"
	      "text-align:right}td:first-child,th:first-child,"
	      "td:last-child{text-align:left}"
	      "img{max-width:100%;image-rendering:pixelated}"
	      ".ok{color:#176}.no{color:#a12}figcaption{font-size:90%}"
	      "</style></head><body>\n<h1>",
	      f);
	esc(f, *name ? name : "material");
	fputs("</h1>\n<p class=\"", f);
	fputs(accepted ? "ok\"><b>Accepted</b>: " : "no\"><b>Refused</b>: ", f);
	esc(f, str(acc, "verdict"));
	fputs(" (", f);
	esc(f, str(acc, "rule"));
	fputs(")</p>\n", f);
	views(f, nviews);
	fprintf(f,
		"<h2>The %s model</h2>\n<table><thead><tr><th>parameter"
		"</th><th>value</th><th>standard error</th><th>%.0f %% "
		"interval</th><th></th></tr></thead><tbody>\n",
		str(doc, "model"), isfinite(level) ? 100 * level : 95.0);
	param_rows(f, json_object_get(doc, "parameters"));
	fprintf(f,
		"</tbody></table>\n<p>Relative RMSE %.4f on %lld pixels; "
		"fitted by ",
		num(doc, "relative_rmse"),
		(long long)json_integer_value(json_object_get(doc, "pixels")));
	esc(f, str(json_object_get(doc, "method"), "name"));
	fprintf(f, " in %.2f s.</p>\n<h2>Residual</h2>\n<p>",
		num(doc, "seconds"));
	esc(f, str(json_object_get(doc, "misfit"), "verdict"));
	fputs("</p>\n<h2>Uncertainty</h2>\n<p>", f);
	esc(f, unc ? str(unc, "method") : "not computed");
	fputs("</p>\n<h2>Inputs</h2>\n<ul><li>scene: ", f);
	esc(f, str(in, "scene"));
	fputs("</li><li>photo: ", f);
	esc(f, str(in, "photo"));
	fputs("</li></ul>\n", f);
	const json_t *ex = json_object_get(doc, "exports");
	if (json_array_size(ex)) {
		size_t k;
		const json_t *e;
		fputs("<h2>Exports</h2>\n<ul>", f);
		json_array_foreach(ex, k, e)
		{
			fputs("<li><a href=\"", f);
			esc(f, str(e, "file"));
			fputs("\">", f);
			esc(f, str(e, "file"));
			fprintf(f, "</a> (%s; refit relative RMS %.3f)</li>",
				str(e, "format"), num(e, "refit_relative_rms"));
		}
		fputs("</ul>\n", f);
	}
	fputs("<p>Everything here is in <a href=\"params.json\">params.json"
	      "</a>.</p>\n</body></html>\n",
	      f);
	if (fclose(f) != 0) {
		free(text);
		return NULL;
	}
	return text;
}
