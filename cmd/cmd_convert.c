/* SPDX-License-Identifier: MIT */
#include "cmd.h"

#include "core/error.h"
#include "core/formats.h"
#include "core/log.h"

#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

void cmd_convert_help(void)
{
	printf("usage: glint convert IN OUT [--half] [--exposure EV] "
	       "[--json]\n"
	       "\n"
	       "Read IN (.exr incl. DWAA/DWAB, .hdr, .pfm) and write OUT "
	       "(.exr, .hdr, .pfm,\n.png); formats follow the extensions. "
	       "Fails, writing nothing, on NaN or\ninfinite pixels.\n"
	       "\n"
	       "  --half         EXR output with half floats\n"
	       "  --exposure EV  PNG exposure in stops (default: auto)\n"
	       "  --allow-nonfinite  copy NaN/Inf values instead of "
	       "failing\n"
	       "  --json         print a JSON result on stdout\n");
}

int cmd_convert(int argc, char **argv)
{
	enum { O_HALF = 256, O_EXPOSURE, O_JSON, O_NONFINITE };
	static const struct option opts[] = {
		{ "half", no_argument, NULL, O_HALF },
		{ "exposure", required_argument, NULL, O_EXPOSURE },
		{ "allow-nonfinite", no_argument, NULL, O_NONFINITE },
		{ "json", no_argument, NULL, O_JSON },
		{ "help", no_argument, NULL, 'h' },
		{ NULL, 0, NULL, 0 },
	};
	struct glint_write_opts wo = { .auto_expose = 1 };
	struct glint_image *img;
	int json = 0, nonfinite = 0, c;

	optind = 1;
	while ((c = getopt_long(argc, argv, "h", opts, NULL)) != -1) {
		switch (c) {
		case O_HALF:
			wo.exr_half = 1;
			break;
		case O_JSON:
			json = 1;
			break;
		case O_NONFINITE:
			nonfinite = 1;
			break;
		case 'h':
			cmd_convert_help();
			return GLINT_EXIT_OK;
		case O_EXPOSURE: {
			char *end;
			wo.exposure = strtod(optarg, &end);
			wo.auto_expose = 0;
			if (*end || !isfinite(wo.exposure))
				return cmd_usage_error("convert",
						       "--exposure '%s': "
						       "expected a number",
						       optarg);
			break;
		}
		default:
			return cmd_usage_error("convert", "unknown option");
		}
	}
	if (json)
		glint_log_set_mode(GLINT_LOG_JSON);
	if (optind != argc - 2)
		return cmd_usage_error("convert", "expected IN and OUT");
	if (glint_image_read(argv[optind], &img) < 0)
		return cmd_fail("convert");
	if (!nonfinite && glint_image_check_finite(img, argv[optind], 0) < 0) {
		glint_image_free(img);
		return cmd_fail("convert");
	}
	if (glint_image_write(argv[optind + 1], img, &wo) < 0) {
		glint_image_free(img);
		return cmd_fail("convert");
	}
	if (json)
		cmd_print_json(json_pack("{s:s,s:s,s:i,s:i}", "input",
					 argv[optind], "output",
					 argv[optind + 1], "width", img->width,
					 "height", img->height));
	else
		glint_log_info("%s -> %s (%dx%d)", argv[optind],
			       argv[optind + 1], img->width, img->height);
	glint_image_free(img);
	return GLINT_EXIT_OK;
}
