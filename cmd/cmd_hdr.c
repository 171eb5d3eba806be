/* SPDX-License-Identifier: MIT */
/*
 * glint hdr: a session's (or a list of) raw frames -> radiance, variance,
 * fit weights and a validity mask (capture/hdr_linear.h, docs/hdr.md).
 */
#define _POSIX_C_SOURCE 200809L
#include "cmd.h"
#include "options.h"

#include "capture/frame_file.h"
#include "capture/hdr_linear.h"
#include "capture/hdr_response.h"
#include "capture/session_merge.h"
#include "core/formats.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/json.h"
#include "core/log.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

void cmd_hdr_help(void)
{
	printf("usage: glint hdr (SESSION_DIR | FRAME.png...) [options]\n"
	       "       glint hdr --times T1,T2,... IMAGE.png... -o DIR "
	       "[--response M]\n"
	       "\n"
	       "Merge a bracket of raw frames (a capture session, or frame "
	       "files written by\nglint capture) into linear radiance with "
	       "noise-optimal weights, zero weight\nfor clipped samples, a "
	       "per-pixel variance and a motion check.  Writes into\nthe "
	       "session (or -o DIR):\n"
	       "  hdr.exr        radiance, DN per second at unity gain "
	       "(demosaiced: bilinear)\n"
	       "  variance.exr   its variance per pixel and channel (0 = "
	       "invalid)\n"
	       "  weights.exr    1 / variance, 0 where invalid: glint fit "
	       "--weights\n"
	       "  mask.png       white = valid, black = clipped in every "
	       "frame\n"
	       "  hdr.png        preview (auto exposure)\n"
	       "  hdr.json       what the merge saw (frames, clipped and dark "
	       "pixels, motion)\n"
	       "\n"
	       "\n8-bit photos (any camera) with --times or --times-file: the "
	       "camera's response\nis recovered (--response robertson, the "
	       "default, or debevec), written to\nresponse.csv, and the "
	       "photos merged; codes at the black floor and at 255 get\nno "
	       "weight (no variance image for 8-bit input).\n\n"
	       "  -o, --output DIR      output folder (default: the session; "
	       "required for files)\n"
	       "      --times LIST      8-bit mode: exposure times in "
	       "seconds, e.g. 32,16,1/2\n"
	       "      --times-file F    the same, one per line\n"
	       "      --response M      robertson (default) or debevec\n"
	       "      --dn-per-electron C  sensor conversion gain at unity "
	       "gain (default: the\n"
	       "                        rig's \"sensor\", else the simulated "
	       "sensor's 0.4095)\n"
	       "      --read-noise E    read noise, electrons (default: rig, "
	       "else 2.5)\n"
	       "      --saturation DN   samples at or above this are clipped "
	       "(default: 95 %% of\n"
	       "                        the range above black)\n"
	       "      --json            print a JSON result on stdout\n"
	       "  -q, --quiet           no info messages\n"
	       "\nExit status: 0 done (a moved bracket is reported, not an "
	       "error), 1 bad input,\n2 bad command line.\n");
}

/* "32", "1/1024", "0.5" */
static int parse_time(const char *s, double *t)
{
	char *end;
	double a = strtod(s, &end);
	if (*end == '/') {
		double b = strtod(end + 1, &end);
		a = b != 0 ? a / b : NAN;
	}
	while (*end == ' ' || *end == '\r' || *end == '\n')
		end++;
	if (*end || !(a > 0) || !isfinite(a))
		return -1;
	*t = a;
	return 0;
}

static int read_times(const char *list, const char *file, int n, double *t)
{
	char buf[8192];
	int k = 0;
	if (file) {
		FILE *f = fopen(file, "r");
		if (!f)
			return glint_error_set(errno, "%s: %s", file,
					       strerror(errno));
		while (k <= n && fgets(buf, sizeof(buf), f)) {
			if (buf[0] == '\n' || buf[0] == '#')
				continue;
			if (k == n || parse_time(buf, &t[k]) < 0) {
				fclose(f);
				return glint_error_set(EINVAL,
						       "%s: line %d: '%.40s': "
						       "expected %d positive "
						       "times (seconds, 1/N "
						       "allowed)",
						       file, k + 1, buf, n);
			}
			k++;
		}
		fclose(f);
	} else {
		snprintf(buf, sizeof(buf), "%s", list);
		for (char *save = NULL, *tok = strtok_r(buf, ",", &save); tok;
		     tok = strtok_r(NULL, ",", &save)) {
			if (k == n || parse_time(tok, &t[k]) < 0)
				return glint_error_set(
					EINVAL,
					"--times: '%s': expected "
					"%d positive times",
					tok, n);
			k++;
		}
	}
	if (k != n)
		return glint_error_set(EINVAL,
				       "%s: %d exposure times for %d images",
				       file ? file : "--times", k, n);
	return 0;
}

static int ldr_main(char **files, int n, const char *times,
		    const char *times_file, const char *method, const char *out,
		    int json)
{
	uint8_t **img = calloc((size_t)n, sizeof(*img));
	double *t = calloc((size_t)n, sizeof(double));
	double resp[256][3];
	struct glint_image *rad = NULL, *valid = NULL;
	int w = 0, h = 0, iters = 0, ret;

	ret = img && t ? 0 : glint_error_set(ENOMEM, "out of memory");
	if (ret == 0)
		ret = read_times(times, times_file, n, t);
	for (int i = 0; i < n && ret == 0; i++) {
		int wi, hi;
		ret = glint_png_read_rgb8(files[i], &wi, &hi, &img[i]);
		if (ret == 0 && i && (wi != w || hi != h))
			ret = glint_error_set(EINVAL,
					      "%s is %dx%d, %s %dx%d: the "
					      "photos must match",
					      files[i], wi, hi, files[0], w, h);
		w = wi;
		h = hi;
	}
	struct glint_ldr_stack s = { n, w, h, (const uint8_t *const *)img, t };
	if (ret == 0)
		ret = glint_ldr_check_order(&s, (const char *const *)files);
	if (ret == 0 && !strcmp(method, "debevec")) {
		struct glint_debevec_opts o;
		glint_debevec_default_opts(&o);
		ret = glint_response_debevec(&s, &o, resp);
	} else if (ret == 0) {
		ret = glint_response_robertson(&s, 30, 0.01, resp, &iters);
	}
	if (ret == 0)
		ret = glint_ldr_merge(&s, resp, NULL, &rad, &valid);
	if (ret == 0 && mkdir(out, 0777) < 0 && errno != EEXIST)
		ret = glint_error_set(errno, "%s: %s", out, strerror(errno));
	char path[4200];
	const char *names[] = { "hdr.exr", "mask.png", "hdr.png" };
	struct glint_image *imgs[] = { rad, valid, rad };
	for (int i = 0; i < 3 && ret == 0; i++) {
		struct glint_write_opts wo = { 0, 0, i == 2 };
		snprintf(path, sizeof(path), "%s/%s", out, names[i]);
		ret = glint_image_write(path, imgs[i], &wo);
	}
	if (ret == 0) {
		char csv[256 * 64];
		size_t k = 0;
		for (int z = 0; z < 256; z++)
			k += (size_t)snprintf(csv + k, sizeof(csv) - k,
					      "%.8g,%.8g,%.8g\n", resp[z][0],
					      resp[z][1], resp[z][2]);
		snprintf(path, sizeof(path), "%s/response.csv", out);
		ret = glint_atomic_write_file(path, csv, k);
	}
	if (ret == 0) {
		glint_log_info("%d photos (%s response%s) -> %s/hdr.exr "
			       "(%dx%d), response.csv",
			       n, method, iters ? ", iterated" : "", out, w, h);
		if (json)
			cmd_print_json(json_pack("{s:s, s:i, s:s, s:i, s:i}",
						 "output", out, "photos", n,
						 "response", method, "width", w,
						 "height", h));
	}
	for (int i = 0; img && i < n; i++)
		free(img[i]);
	free(img);
	free(t);
	glint_image_free(rad);
	glint_image_free(valid);
	return ret < 0 ? cmd_fail("hdr") : GLINT_EXIT_OK;
}

int cmd_hdr(int argc, char **argv)
{
	static const char *const responses[] = { "robertson", "debevec", NULL };
	const char *out = NULL, *times = NULL, *times_file = NULL;
	double cpe = NAN, rn = NAN, sat = NAN;
	int response = 0, ret;
	const struct cmd_opt opts[] = {
		CMD_STRING("output", 'o', &out),
		CMD_REAL("dn-per-electron", &cpe, 1e-9, 1e9),
		CMD_REAL("read-noise", &rn, 0, 1e9),
		CMD_REAL("saturation", &sat, 1, 1e12),
		CMD_STRING("times", 0, &times),
		CMD_STRING("times-file", 0, &times_file),
		CMD_CHOICE("response", &response, responses),
		{ 0 },
	};
	struct cmd_args a;
	int r = cmd_options_parse("hdr", cmd_hdr_help, opts, argc, argv, &a);
	if (r)
		return cmd_options_exit(r);
	int json = a.json;
	const char *method = responses[response];
	argc = a.argc;
	argv = a.argv;
	if (argc < 1)
		return cmd_usage_error("hdr", "expected a session folder or "
					      "frame files");
	if (times || times_file) {
		if (!out)
			return cmd_usage_error("hdr",
					       "8-bit photos need -o DIR");
		return ldr_main(argv, argc, times, times_file, method, out,
				json);
	}

	struct glint_noise_model nm;
	struct glint_frame *frames = NULL;
	struct glint_hdr_report rep;
	static const char *const hdr_names[5] = { "hdr.exr", "variance.exr",
						  "weights.exr", "mask.png",
						  "hdr.png" };
	int n = 0, width = 0, height = 0;
	long valid_px = 0;
	char path[4200];
	struct stat st;
	glint_noise_default(&nm);
	/* One argument that is not a file: a session (or an error naming
	 * its session.json). */
	int is_session =
		argc == 1 && !(stat(argv[0], &st) == 0 && S_ISREG(st.st_mode));
	if (is_session) {
		ret = glint_session_noise(argv[0], &nm);
		if (ret == 0)
			ret = glint_session_load_frames(argv[0], &frames, &n);
		if (!out)
			out = argv[0];
	} else {
		if (!out)
			return cmd_usage_error("hdr",
					       "frame files need -o DIR");
		n = argc;
		frames = calloc((size_t)n, sizeof(*frames));
		ret = frames ? 0 : glint_error_set(ENOMEM, "out of memory");
		for (int i = 0; i < n && ret == 0; i++)
			ret = glint_frame_read(argv[i], &frames[i], NULL);
	}
	if (!isnan(cpe))
		nm.dn_per_electron = cpe;
	if (!isnan(rn))
		nm.read_noise_e = rn;
	if (!isnan(sat))
		nm.saturation_dn = sat;
	if (ret == 0)
		ret = glint_hdr_merge_write(frames, n, &nm, out, hdr_names,
					    &rep, &width, &height, &valid_px,
					    NULL);
	json_t *res = NULL;
	if (ret == 0) {
		json_t *pairs = json_array();
		for (int i = 0; i < rep.pairs; i++)
			json_array_append_new(
				pairs, json_pack("{s:i, s:I, s:f}", "pair", i,
						 "compared",
						 (json_int_t)rep.compared[i],
						 "disagree_fraction",
						 rep.disagree[i]));
		res = json_pack(
			"{s:s, s:i, s:i, s:i, s:I, s:I, s:I, s:b, s:o, "
			"s:{s:f, s:f, s:f}}",
			"output", out, "frames", n, "width", width, "height",
			height, "valid_pixels", (json_int_t)valid_px,
			"clipped_sites", (json_int_t)rep.invalid_sites,
			"dark_sites", (json_int_t)rep.dark_sites, "moved",
			rep.moved, "motion", pairs, "noise_model",
			"dn_per_electron", nm.dn_per_electron, "read_noise_e",
			nm.read_noise_e, "saturation_dn", nm.saturation_dn);
		char *text = json_dumps(res, JSON_INDENT(2));
		snprintf(path, sizeof(path), "%s/hdr.json", out);
		ret = text ? glint_atomic_write_file(path, text, strlen(text))
			   : glint_error_set(ENOMEM, "out of memory");
		free(text);
	}
	if (ret == 0) {
		if (rep.moved)
			glint_log_warn("frames of the bracket "
				       "disagree where both are well exposed "
				       "(moved rig or scene?): see %s/hdr.json",
				       out);
		glint_log_info("%d frames -> %s/hdr.exr (%dx%d), %ld of %ld "
			       "pixels valid, %ld sites clipped in every "
			       "frame",
			       n, out, width, height, valid_px,
			       (long)width * height, rep.invalid_sites);
		if (json)
			cmd_print_json(res);
		else
			json_decref(res);
	}
	glint_frames_free(frames, n);
	return ret < 0 ? cmd_fail("hdr") : GLINT_EXIT_OK;
}
