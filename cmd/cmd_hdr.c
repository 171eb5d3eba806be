/* SPDX-License-Identifier: MIT */
/*
 * glint hdr: a session's (or a list of) raw frames -> radiance, variance,
 * fit weights and a validity mask (capture/hdr/hdr_linear.h, docs/hdr.md).
 */
#define _POSIX_C_SOURCE 200809L
#include "cmd.h"
#include "options.h"

#include "capture/hdr/frame_file.h"
#include "capture/hdr/hdr_linear.h"
#include "capture/hdr/hdr_files.h"
#include "capture/hdr/raw_file.h"
#include "capture/hdr/session_merge.h"
#include "core/error.h"
#include "core/json.h"
#include "core/log.h"
#include "core/output.h"
#include "core/path.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

void cmd_hdr_help(void)
{
	printf("usage: glint hdr SESSION_DIR [options]\n"
	       "       glint hdr RAW... -o DIR [--times T1,T2,...] "
	       "[options]\n"
	       "       glint hdr --times T1,T2,... IMAGE.png... -o DIR "
	       "[--response M]\n"
	       "       glint hdr PHOTO.jpg|PHOTO.tif... -o DIR (times from "
	       "EXIF)\n"
	       "\n"
	       "Merge a bracket of raw frames into linear radiance with "
	       "noise-optimal weights,\nzero weight for clipped samples, a "
	       "per-pixel variance and a motion check,\nfolding the frames "
	       "in one at a time (a session's as its capture did: the "
	       "same\nresult).  RAW files: glint's own frames, any camera's "
	       "raw files LibRaw reads\n(DNG, CR2/CR3, NEF, ARW, RAF, ORF, "
	       "RW2, ...: exposure, ISO, black and white\nlevels, the CFA "
	       "pattern and the colour matrix from their metadata; camera "
	       "RGB\nturned into linear sRGB), or a converter's 16-bit "
	       "linear TIFFs (dcraw -4 -T).\nAnother camera's conversion "
	       "gain comes from the bracket (photon transfer)\nunless "
	       "--dn-per-electron is given.\n"
	       "Writes into the session (or -o DIR):\n"
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
	       "pixels, motion,\n"
	       "                 the files' reader, camera, levels, colour "
	       "matrix, noise)\n"
	       "\n8-bit photos (any camera: JPEG, 8-bit PNG or TIFF) with "
	       "--times or --times-file,\nor JPEG and TIFF photos with "
	       "their exposure times in EXIF: the camera's response\nis "
	       "recovered (--response robertson, the default, or debevec), "
	       "written to\nresponse.csv and drawn in response.png, and the "
	       "photos merged; codes at the\nblack floor and at 255 get no "
	       "weight (no variance image for 8-bit input).\n\n"
	       "  -o, --output DIR      output folder (default: the session; "
	       "required for files)\n"
	       "      --times LIST      exposure times in seconds, e.g. "
	       "32,16,1/2 (8-bit photos;\n"
	       "                        raw files without their own, or "
	       "in place of them)\n"
	       "      --times-file F    the same, one per line\n"
	       "      --response M      robertson (default) or debevec\n"
	       "      --dn-per-electron C  sensor conversion gain at unity "
	       "gain (default: the\n"
	       "                        rig's \"sensor\"; another camera's "
	       "files: from the\n"
	       "                        bracket; glint's frames: the "
	       "simulated sensor's 0.4095)\n"
	       "      --read-noise E    read noise, electrons (default: rig, "
	       "else 2.5)\n"
	       "      --saturation DN   samples at or above this are clipped "
	       "(default: 95 %% of\n"
	       "                        the range above black)\n"
	       "      --force           replace the files named above if "
	       "glint wrote them\n"
	       "                        (a session's own are replaced by "
	       "its next merge)\n"
	       "                        (existing ones are refused without "
	       "it; another's files\n"
	       "                        or the inputs, always)\n"
	       "      --json            print a JSON result on stdout\n"
	       "  -q, --quiet           no info messages\n"
	       "\nA raw bracket whose frames disagree beyond their noise (a "
	       "moved rig, or frames of\nanother scene among them) is "
	       "refused, naming the pair; nothing is merged.\n"
	       "\nExit status: 0 done, 1 bad input (a mixed or moved bracket "
	       "among it),\n2 bad command line.\n");
}

/* Each file hdr writes into folder out (names, NULL-terminated), by the
 * one overwrite rule (core/output.h); the n inputs are never replaced. */
static int outputs_check(const char *out, const char *const *names, int force,
			 char **inputs, int n)
{
	char path[GLINT_PATH_MAX];
	const char **in = calloc((size_t)n + 1, sizeof(*in));
	int ret = in ? 0 : glint_error_set(ENOMEM, "out of memory");
	for (int k = 0; k < n && in; k++)
		in[k] = inputs[k];
	for (int k = 0; ret == 0 && names[k]; k++) {
		ret = glint_path_join(path, sizeof(path), out, names[k]);
		if (ret == 0)
			ret = glint_output_check(path, force, in);
	}
	free(in);
	return ret;
}

static int ldr_main(char **files, int n, const char *times,
		    const char *times_file, const char *method, const char *out,
		    int json)
{
	struct glint_ldr_merge_info info;
	double *t = calloc((size_t)n, sizeof(double));
	int ret = t ? 0 : glint_error_set(ENOMEM, "out of memory");
	const char *source = times_file ? "--times-file"
			     : times	? "--times"
					: "EXIF";

	if (ret == 0 && (times || times_file))
		ret = glint_exposure_times_read(times, times_file, n, t);
	else if (ret == 0)
		ret = glint_exposure_times_exif((const char *const *)files, n,
						t);
	if (ret == 0)
		ret = glint_ldr_merge_files((const char *const *)files, n, t,
					    method, out, &info);
	json_t *tj = json_array();
	for (int i = 0; ret == 0 && i < n; i++)
		json_array_append_new(tj, json_real(t[i]));
	free(t);
	if (ret < 0) {
		json_decref(tj);
		return cmd_fail("hdr");
	}
	glint_log_info("%d photos (%s response%s, times from %s) -> "
		       "%s/hdr.exr (%dx%d), response.csv and .png",
		       n, method, info.iterations ? ", iterated" : "", source,
		       out, info.width, info.height);
	if (json)
		cmd_print_json(json_pack("{s:s, s:i, s:s, s:i, s:i, s:o, s:s}",
					 "output", out, "photos", n, "response",
					 method, "width", info.width, "height",
					 info.height, "exposure_times_s", tj,
					 "times_from", source));
	else
		json_decref(tj);
	return GLINT_EXIT_OK;
}

int cmd_hdr(int argc, char **argv)
{
	static const char *const responses[] = { "robertson", "debevec", NULL };
	const char *out = NULL, *times = NULL, *times_file = NULL;
	double cpe = NAN, rn = NAN, sat = NAN;
	int response = 0, force = 0, ret;
	const struct cmd_opt opts[] = {
		CMD_STRING("output", 'o', &out),
		CMD_REAL("dn-per-electron", &cpe, 1e-9, 1e9),
		CMD_REAL("read-noise", &rn, 0, 1e9),
		CMD_REAL("saturation", &sat, 1, 1e12),
		CMD_STRING("times", 0, &times),
		CMD_STRING("times-file", 0, &times_file),
		CMD_CHOICE("response", &response, responses),
		CMD_FLAG("force", 0, &force),
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
	/* A folder is a session; of files, 8-bit photos (JPEG, 8-bit PNG
	 * and TIFF) with their times given, or from EXIF; everything else
	 * is raw. */
	struct stat st;
	int first_is_dir = stat(argv[0], &st) == 0 && S_ISDIR(st.st_mode);
	int ldr = first_is_dir ? 0 : glint_raw_file_is_8bit(argv[0]);
	if (ldr < 0)
		return cmd_fail("hdr");
	if (ldr) {
		if (!out)
			return cmd_usage_error("hdr",
					       "8-bit photos need -o DIR");
		static const char *const ldr_names[] = {
			"hdr.exr",	"mask.png",	"hdr.png",
			"response.csv", "response.png", NULL
		};
		if (outputs_check(out, ldr_names, force, argv, argc) < 0)
			return cmd_fail("hdr");
		return ldr_main(argv, argc, times, times_file, method, out,
				json);
	}

	struct glint_noise_model nm;
	struct glint_frame *frames = NULL;
	struct glint_raw_info info = { 0 };
	json_t *input = NULL;
	struct glint_hdr_report rep;
	static const char *const hdr_names[5] = { "hdr.exr", "variance.exr",
						  "weights.exr", "mask.png",
						  "hdr.png" };
	int n = 0, width = 0, height = 0;
	long valid_px = 0;
	glint_noise_default(&nm);
	/* One folder: a session (or an error naming its session.json). */
	int is_session = argc == 1 && first_is_dir;
	/* A session's own folder holds its latest merge (the rig's): a
	 * merge of it there replaces it; a folder named with -o follows the
	 * one overwrite rule. */
	if (is_session && (times || times_file))
		return cmd_usage_error(
			"hdr", "--times: a session's frames carry their "
			       "own exposure times");
	int own = is_session && !out;
	if (is_session) {
		ret = glint_session_noise(argv[0], &nm);
		if (!out)
			out = argv[0];
	} else {
		if (!out)
			return cmd_usage_error("hdr",
					       "frame files need -o DIR");
		n = argc;
		double *t = NULL;
		ret = 0;
		if (times || times_file) {
			t = calloc((size_t)n, sizeof(*t));
			ret = t ? glint_exposure_times_read(times, times_file,
							    n, t)
				: glint_error_set(ENOMEM, "out of memory");
		}
		if (ret == 0)
			ret = glint_frames_read((const char *const *)argv, n, t,
						&frames, &info);
		free(t);
		if (ret == 0)
			input = glint_raw_input_json(
				&info, &frames[0],
				times_file ? "--times-file"
				: times	   ? "--times"
					   : "the files' metadata");
	}
	static const char *const all_names[] = { "hdr.exr",	"variance.exr",
						 "weights.exr", "mask.png",
						 "hdr.png",	"hdr.json",
						 NULL };
	if (ret == 0 && !own)
		ret = outputs_check(out, all_names, force, argv,
				    is_session ? 0 : argc);
	/* Another camera's files: its conversion gain from the bracket
	 * itself, unless given. */
	const char *noise_from = is_session
					 ? "the session's rig.json"
					 : "glint's simulated sensor (default)";
	long used = 0;
	if (ret == 0 && !is_session && isnan(cpe) &&
	    strcmp(info.reader, "glint frame") != 0) {
		ret = glint_noise_from_bracket(frames, n, &nm, &used);
		if (used)
			noise_from = "the bracket (photon transfer)";
	}
	if (!isnan(cpe))
		noise_from = "--dn-per-electron";
	if (input) {
		json_object_set_new(input, "noise_model_from",
				    json_string(noise_from));
		json_object_set_new(input, "photon_transfer_sites",
				    json_integer(used));
	}
	if (!isnan(cpe))
		nm.dn_per_electron = cpe;
	if (!isnan(rn))
		nm.read_noise_e = rn;
	if (!isnan(sat))
		nm.saturation_dn = sat;
	/* A session is folded in one frame at a time, as the rig merged it
	 * (the same bits); frame files are read first (named: checked
	 * before any work). */
	if (ret == 0 && is_session)
		ret = glint_session_merge_write(argv[0], &nm, out, hdr_names,
						&rep, &width, &height,
						&valid_px);
	else if (ret == 0)
		ret = glint_hdr_merge_write(
			frames, n, &nm, info.has_matrix ? info.rgb_cam : NULL,
			out, hdr_names, &rep, &width, &height, &valid_px, NULL);
	if (ret == 0)
		n = rep.frames;
	json_t *res = NULL;
	if (ret == 0)
		ret = glint_hdr_report_write(out, n, width, height, valid_px,
					     &rep, &nm, input, &res);
	else
		json_decref(input);
	if (ret == 0) {
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
