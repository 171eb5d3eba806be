/* SPDX-License-Identifier: MIT */
/* Every real light probe in ../shared/data reads with plausible values. */
#include "test.h"

#include "core/error.h"
#include "core/image.h"
#include "core/vec.h"

static const struct {
	const char *path;
	int w, h;
} probes[] = {
	{ "probes/probulator_small/ennis.hdr", 256, 128 },
	{ "probes/probulator_small/grace.hdr", 256, 128 },
	{ "probes/probulator_small/pisa.hdr", 256, 128 },
	{ "probes/probulator_small/uffizi.hdr", 256, 128 },
	{ "probes/probulator_small/wells.hdr", 256, 128 },
	{ "probes/polyhaven_1k/venice_sunset_1k.hdr", 1024, 512 },
	{ "probes/polyhaven_1k/royal_esplanade_1k.hdr", 1024, 512 },
	{ "probes/polyhaven_1k/quarry_01_1k.hdr", 1024, 512 },
	{ "probes/campus_probe.hdr", 640, 640 },
	{ "probes/blender_studiolights/studio.exr", 1024, 512 },
	{ "probes/blender_studiolights/courtyard.exr", 1024, 512 },
};

int main(void)
{
	if (!shared_file("README.md")) {
		printf("skip: %s is absent\n", GLINT_SHARED_DATA);
		return 77;
	}
	for (size_t i = 0; i < sizeof(probes) / sizeof(probes[0]); i++) {
		const char *p = shared_file(probes[i].path);
		struct glint_image *img = NULL;
		CHECK(p != NULL, "%s missing", probes[i].path);
		if (!p)
			continue;
		CHECK(glint_image_read(p, &img) == 0, "%s", glint_error_msg());
		if (!img)
			continue;
		CHECK(img->width == probes[i].w && img->height == probes[i].h,
		      "%s: %dx%d", probes[i].path, img->width, img->height);
		/* Plausible radiance: finite, non-negative, a dynamic range
		 * beyond 8 bits, nothing absurd. */
		double mn = 1e30, mx = 0, sum = 0;
		size_t n = (size_t)img->width * img->height, nonfinite = 0;
		for (size_t k = 0; k < n; k++) {
			const float *q = img->data + 3 * k;
			if (!isfinite(q[0]) || !isfinite(q[1]) ||
			    !isfinite(q[2])) {
				nonfinite++;
				continue;
			}
			double l = rgb_luminance(q[0], q[1], q[2]);
			mn = fmin(mn, l);
			mx = fmax(mx, l);
			sum += l;
		}
		CHECK(nonfinite == 0, "%s: %zu non-finite", probes[i].path,
		      nonfinite);
		/* DWAB ringing dips a little below zero (courtyard.exr). */
		CHECK(mn >= -0.01 * sum / n && mx < 1e6 && mx > 0,
		      "%s: luminance %g .. %g", probes[i].path, mn, mx);
		CHECK(mx / (sum / n) > 4, "%s: max %g only %g x the mean",
		      probes[i].path, mx, mx / (sum / n));
		fprintf(stderr, "  %-45s %4dx%-4d mean %8.4f max %10.2f\n",
			probes[i].path, img->width, img->height, sum / n, mx);
		glint_image_free(img);
	}
	return test_result();
}
