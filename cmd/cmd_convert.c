/* SPDX-License-Identifier: MIT */
#include "cmd.h"
#include "options.h"

#include "core/error.h"
#include "core/formats.h"
#include "core/log.h"
#include "core/output.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

void cmd_convert_help(void)
{
	printf("usage: glint convert IN OUT [--half] [--exposure EV] [--srgb] "
	       "[--force] [--json]\n"
	       "\n"
	       "Read IN (.exr incl. DWAA/DWAB, .hdr, .pfm, .tif: float or "
	       "16-bit linear)\nand write OUT (.exr, .hdr, .pfm, .tif: 32-bit "
	       "float, .png); formats follow\nthe extensions. "
	       "Fails, writing nothing, on NaN or\ninfinite pixels.\n"
	       "\n"
	       "  -o, --output OUT  the output (instead of the second "
	       "argument)\n"
	       "  --half         EXR output with half floats\n"
	       "  --srgb         IN is 8-bit (.png, .jpg, ...) and OUT a float "
	       "format: take IN\n"
	       "                 as sRGB-encoded and linearise it (without it "
	       "such a\n"
	       "                 conversion is refused: 8-bit values are "
	       "camera-encoded,\n"
	       "                 not radiance)\n"
	       "  --exposure EV  PNG exposure in stops (default: auto)\n"
	       "  --allow-nonfinite  copy NaN/Inf values instead of "
	       "failing\n"
	       "  --force        replace OUT if glint wrote it (an existing "
	       "OUT is refused\n"
	       "                 without it; a file glint did not write, "
	       "or IN, always)\n"
	       "  --json         print a JSON result on stdout\n");
}

int cmd_convert(int argc, char **argv)
{
	struct glint_write_opts wo = { .auto_expose = 1 };
	struct glint_image *img;
	const char *out = NULL;
	double exposure = NAN;
	int nonfinite = 0, srgb = 0, force = 0;
	const struct cmd_opt opts[] = {
		CMD_FLAG("srgb", 0, &srgb),
		CMD_FLAG("half", 0, &wo.exr_half),
		CMD_REAL("exposure", &exposure, -64, 64),
		CMD_FLAG("allow-nonfinite", 0, &nonfinite),
		CMD_STRING("output", 'o', &out),
		CMD_FLAG("force", 0, &force),
		{ 0 },
	};
	struct cmd_args a;
	int r = cmd_options_parse("convert", cmd_convert_help, opts, argc, argv,
				  &a);
	if (r)
		return cmd_options_exit(r);
	int json = a.json;
	if (isfinite(exposure)) {
		wo.exposure = exposure;
		wo.auto_expose = 0;
	}
	/* IN OUT, or IN -o OUT */
	if (a.argc != 2 - (out != NULL))
		return cmd_usage_error("convert", "expected IN and OUT (or IN "
						  "-o OUT)");
	if (!out)
		out = a.argv[1];
	argv = a.argv;
	const char *inputs[] = { argv[0], NULL };
	if (glint_output_check(out, force, inputs) < 0)
		return cmd_fail("convert");
	/* To a float format the values become radiance: the one policy.
	 * 8-bit to 8-bit (a PNG preview) copies them. */
	int to_ldr = glint_image_encoded(out);
	if ((to_ldr ? glint_image_read(argv[0], &img)
		    : glint_image_read_radiance(argv[0], srgb, &img)) < 0)
		return cmd_fail("convert");
	if (!nonfinite && glint_image_check_finite(img, argv[0], 0) < 0) {
		glint_image_free(img);
		return cmd_fail("convert");
	}
	if (glint_image_write(out, img, &wo) < 0) {
		glint_image_free(img);
		return cmd_fail("convert");
	}
	if (json)
		cmd_print_json(json_pack("{s:s,s:s,s:i,s:i}", "input", argv[0],
					 "output", out, "width", img->width,
					 "height", img->height));
	else
		glint_log_info("%s -> %s (%dx%d)", argv[0], out, img->width,
			       img->height);
	glint_image_free(img);
	return GLINT_EXIT_OK;
}
