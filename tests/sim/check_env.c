/* SPDX-License-Identifier: MIT */
/*
 * check_env ENV.exr MASK.png TRUTH MAX_MEDIAN: the median relative
 * luminance error of an unwrapped probe against the map it reflects (an
 * image file, or "sim-rig": the sim rig's map, sim/camera_sim.h)
 * (resampled to the same size), over the texels its mask calls reliable;
 * exit 1 above MAX_MEDIAN.  Scale is free (the sensor's units): the
 * median ratio is divided out.
 */
#include "capture/probe/probe.h"
#include "core/error.h"
#include "sim/camera_sim.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int cmp(const void *a, const void *b)
{
	double x = *(const double *)a, y = *(const double *)b;
	return (x > y) - (x < y);
}

static double lum(const float *p)
{
	return 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
}

int main(int argc, char **argv)
{
	struct glint_image *env, *mask, *truth, *t;
	if (argc != 5 || glint_image_read(argv[1], &env) < 0 ||
	    glint_image_read(argv[2], &mask) < 0 ||
	    (strcmp(argv[3], "sim-rig") ? glint_image_read(argv[3], &truth)
					: glint_sim_rig_map(1, &truth)) < 0 ||
	    glint_probe_convert(truth, GLINT_PROBE_LATLONG, GLINT_PROBE_LATLONG,
				env->width, env->height, &t) < 0) {
		fprintf(stderr, "check_env: %s\n", glint_error_msg());
		return 1;
	}
	size_t n = (size_t)env->width * env->height, m = 0;
	double *r = malloc(n * sizeof(double)), *e = malloc(n * sizeof(double));
	for (size_t i = 0; i < n; i++)
		if (mask->data[3 * i] > 0.5 && lum(t->data + 3 * i) > 0 &&
		    lum(env->data + 3 * i) > 0)
			r[m++] = lum(env->data + 3 * i) / lum(t->data + 3 * i);
	qsort(r, m, sizeof(double), cmp);
	if (m == 0) {
		fprintf(stderr, "check_env: no reliable texel\n");
		return 1;
	}
	double scale = r[m / 2];
	for (size_t i = 0; i < m; i++)
		e[i] = fabs(r[i] / scale - 1);
	qsort(e, m, sizeof(double), cmp);
	double limit = atof(argv[4]);
	printf("unwrapped probe vs its map: median |error| %.4f, 90th "
	       "percentile %.4f over %zu reliable texels (%.1f %%)\n",
	       e[m / 2], e[m * 9 / 10], m, 100.0 * m / n);
	int ok = e[m / 2] <= limit && m > n / 2;
	free(r);
	free(e);
	glint_image_free(env);
	glint_image_free(mask);
	glint_image_free(truth);
	glint_image_free(t);
	return ok ? 0 : 1;
}
