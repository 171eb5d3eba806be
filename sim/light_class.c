/* SPDX-License-Identifier: MIT */
/*
 * Lighting classes (light_class.h): a smooth background per class,
 * evaluated at each texel's centre, then discs and az/el rectangles
 * painted over it with their coverage of each texel sampled k x k.
 *
 * Angles are in degrees: azimuth az = atan2(x, -z) (0 looking down -Z,
 * 180 toward the camera on +Z, 90 toward +X), elevation el above the
 * horizon.  Colours are linear Rec.709; (1, 1, 1) is a D65 white.
 */
#define _DEFAULT_SOURCE
#include "light_class.h"

#include "core/error.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define DEG (M_PI / 180)

enum shape_kind { DISC, RECT };
enum shape_op {
	ADD,  /* a lamp: added to what is behind it */
	OVER, /* a window, a card: hides what is behind it */
	SMALL /* a lamp whose rgb is its irradiance at normal incidence */
};

struct shape {
	enum shape_kind kind;
	enum shape_op op;
	double az, el;		 /* centre */
	double half_az, half_el; /* RECT: half extents; DISC: half_az radius */
	double soft;		 /* RECT: width of the edge's linear ramp */
	double rgb[3];		 /* radiance, or irradiance (SMALL) */
};

struct light_class {
	const char *name;
	void (*background)(double az, double el, double rgb[3]);
	const struct shape *shapes;
	int nshapes;
};

static void set3(double rgb[3], double s, double r, double g, double b)
{
	rgb[0] = s * r;
	rgb[1] = s * g;
	rgb[2] = s * b;
}

/* Warm white of a tungsten lamp (illuminant A's chromaticity). */
#define TUNGSTEN 1.0, 0.62, 0.30
#define SODIUM	 1.0, 0.52, 0.10
#define LED	 1.0, 0.86, 0.70 /* 4000 K */

/* An interior: ceiling, walls a little brighter on the windows' side,
 * a wooden floor. */
static void room_bg(double az, double el, double rgb[3])
{
	if (el > 55)
		set3(rgb, 0.10, 1.0, 0.97, 0.92);
	else if (el > -10)
		set3(rgb, 0.06 * (0.8 + 0.2 * cos((az - 130) * DEG)), 1.0, 0.93,
		     0.82);
	else
		set3(rgb, 0.035, 0.9, 0.7, 0.5);
}

/* A pane of sky (s: its radiance) and a box of grey light. */
#define PANE(az, el, haz, hel, s)                                              \
	{                                                                      \
		RECT, OVER, az, el, haz, hel, 0,                               \
		{                                                              \
			(s) * 0.85, (s)*0.95, (s)*1.1                          \
		}                                                              \
	}
#define BOX(az, el, haz, hel, soft, L)                                         \
	{                                                                      \
		RECT, OVER, az, el, haz, hel, soft,                            \
		{                                                              \
			L, L, L                                                \
		}                                                              \
	}
/* A lamp of a radius in degrees, irradiance e and a colour (r, g, b). */
#define LAMP(az, el, radius, e, colour) LAMP_(az, el, radius, e, colour)
#define LAMP_(az, el, radius, e, r, g, b)                                      \
	{                                                                      \
		DISC, SMALL, az, el, radius, 0, 0,                             \
		{                                                              \
			(e) * (r), (e) * (g), (e) * (b)                        \
		}                                                              \
	}

/* Two windows of 2 x 2 panes (mullions 2 degrees) near the horizon: one
 * on the camera's right (az 120-170, el -5 to 38), one behind on the
 * right (az 45-85, el 0-32); the upper panes see more sky.  The sun
 * through the first lies on the floor. */
static const struct shape room_shapes[] = {
	PANE(132, 5.25, 12, 10.25, 2.2),
	PANE(158, 5.25, 12, 10.25, 2.2),
	PANE(132, 27.75, 12, 10.25, 3.0),
	PANE(158, 27.75, 12, 10.25, 3.0),
	PANE(54.5, 7.5, 9.5, 7.5, 1.5),
	PANE(75.5, 7.5, 9.5, 7.5, 1.5),
	PANE(54.5, 24.5, 9.5, 7.5, 2.1),
	PANE(75.5, 24.5, 9.5, 7.5, 2.1),
	{ RECT, OVER, 145, -33.5, 15, 8.5, 2, { 0.9, 0.81, 0.675 } },
};

static void studio_bg(double az, double el, double rgb[3])
{
	(void)az;
	set3(rgb, el < -15 ? 0.04 : 0.015, 1, 1, 1);
}

/* Key (front left, 30 degrees up), fill (front right, low), rim (behind
 * right, high): soft-edged boxes. */
static const struct shape studio_shapes[] = {
	BOX(-135, 30, 22, 16, 3, 6),
	BOX(150, 10, 28, 22, 5, 1.2),
	BOX(20, 45, 8, 18, 2, 8),
};

/* The CIE standard overcast sky, L = Lz (1 + 2 sin el) / 3, zenith 1.2;
 * the ground of albedo 0.2 under it: 0.2 E / pi with E = 7 pi Lz / 9. */
static void overcast_bg(double az, double el, double rgb[3])
{
	(void)az;
	if (el >= 0)
		set3(rgb, 1.2 * (1 + 2 * sin(el * DEG)) / 3, 0.95, 1.0, 1.07);
	else
		set3(rgb, 0.2 * 7 * 1.2 / 9, 0.9, 0.85, 0.75);
}

#define SUN_AZ 160.0
#define SUN_EL 35.0

/* A clear sky: blue, brighter toward the horizon and around the sun;
 * the ground lit by sun and sky. */
static void sun_sky_bg(double az, double el, double rgb[3])
{
	if (el < 0) {
		set3(rgb, 0.3, 0.8, 0.9, 0.6);
		return;
	}
	double ca = cos(az * DEG), sa = sin(az * DEG), ce = cos(el * DEG);
	double cs = cos(SUN_AZ * DEG), ss = sin(SUN_AZ * DEG),
	       cse = cos(SUN_EL * DEG);
	double dot = ce * cse * (ca * cs + sa * ss) +
		     sin(el * DEG) * sin(SUN_EL * DEG);
	double gamma = acos(fmax(-1, fmin(1, dot))) / DEG;
	double s =
		0.35 * (0.5 + 1.5 * exp(-el / 12)) * (1 + 3 * exp(-gamma / 8));
	set3(rgb, s, 0.55, 0.75, 1.1);
}

/* The sun: 0.53 degrees across, irradiance about 6 x the sky's on a
 * horizontal surface. */
static const struct shape sun_sky_shapes[] = {
	LAMP_(SUN_AZ, SUN_EL, 0.265, 1, 9.0, 8.8, 8.4),
};

static void lamp_room_bg(double az, double el, double rgb[3])
{
	(void)az;
	(void)el;
	set3(rgb, 0.015, TUNGSTEN);
}

/* A small tungsten lamp front left, and a white card catching some of
 * its light on the right. */
static const struct shape lamp_fill_shapes[] = {
	LAMP(-150, 25, 1.5, 4, TUNGSTEN),
	{ RECT, OVER, 120, 0, 25, 20, 4, { 0.25, 0.25 * 0.9, 0.25 * 0.8 } },
};

/* A dark sky with a glow at the horizon, dark ground. */
static void night_bg(double az, double el, double rgb[3])
{
	(void)az;
	if (el < 0) {
		set3(rgb, 0.003, 1, 1, 1);
		return;
	}
	double glow = 0.01 * exp(-el / 6);
	rgb[0] = 0.004 * 0.5 + glow * 1.0;
	rgb[1] = 0.004 * 0.6 + glow * 0.6;
	rgb[2] = 0.004 * 1.0 + glow * 0.3;
}

/* Sodium lamps (1, 0.52, 0.10) and 4000 K LEDs (1, 0.86, 0.70), 0.6 to 2
 * degrees across, most near the horizon and two behind the sphere. */
static const struct shape night_shapes[] = {
	LAMP(-160, 12, 0.6, 0.8, SODIUM), LAMP(150, 20, 0.4, 0.6, LED),
	LAMP(110, 6, 0.8, 0.5, SODIUM),	  LAMP(-100, 30, 0.3, 0.4, LED),
	LAMP(40, 15, 0.5, 0.5, LED),	  LAMP(-30, 4, 1.0, 0.3, SODIUM),
};

#define N(a) ((int)(sizeof(a) / sizeof((a)[0])))
static const struct light_class classes[] = {
	{ "window-room", room_bg, room_shapes, N(room_shapes) },
	{ "softbox-studio", studio_bg, studio_shapes, N(studio_shapes) },
	{ "overcast", overcast_bg, NULL, 0 },
	{ "sun-sky", sun_sky_bg, sun_sky_shapes, N(sun_sky_shapes) },
	{ "lamp-fill", lamp_room_bg, lamp_fill_shapes, N(lamp_fill_shapes) },
	{ "night-lamps", night_bg, night_shapes, N(night_shapes) },
};

const char *const glint_sim_light_classes[] = {
	"window-room", "softbox-studio", "overcast", "sun-sky",
	"lamp-fill",   "night-lamps",	 NULL,
};

static const struct light_class *find_class(const char *name)
{
	for (int i = 0; i < N(classes); i++)
		if (name && !strcmp(name, classes[i].name))
			return &classes[i];
	glint_error_set(EINVAL,
			"light class '%s': not one of window-room, "
			"softbox-studio, overcast, sun-sky, lamp-fill, "
			"night-lamps",
			name ? name : "(none)");
	return NULL;
}

static struct vec3 dir_of(double az, double el)
{
	return glint_latlong_uv_to_dir(0.5 + az / 360, (90 - el) / 180);
}

static double wrap180(double a)
{
	a = fmod(a + 180, 360);
	return (a < 0 ? a + 360 : a) - 180;
}

static double ramp(double x, double soft)
{
	if (soft <= 0)
		return x >= 0;
	x = x / soft + 0.5;
	return x < 0 ? 0 : x > 1 ? 1 : x;
}

/* The shape's profile (0 to 1) in direction (az, el) = d. */
static double profile(const struct shape *s, struct vec3 c, double az,
		      double el, struct vec3 d)
{
	if (s->kind == DISC)
		return v3_dot(d, c) >= cos(s->half_az * DEG);
	return ramp(s->half_az - fabs(wrap180(az - s->az)), s->soft) *
	       ramp(s->half_el - fabs(el - s->el), s->soft);
}

/* Paint shape s on img.  pass 0 sums the solid angle it covers weighted
 * by the cosine to its centre (for a SMALL one's radiance); pass 1
 * paints radiance L. */
static double paint(struct glint_image *img, const struct shape *s,
		    const double L[3], int pass)
{
	const int w = img->width, h = img->height;
	const int k = s->kind == DISC ? 8 : 4;
	const double texel = 180.0 / h, margin = 2 * texel;
	double ext_el =
		(s->kind == DISC ? s->half_az : s->half_el) + s->soft + margin;
	double ext_az = s->kind == DISC ? s->half_az + margin
					: s->half_az + s->soft + margin;
	double top = s->el + ext_el, bottom = s->el - ext_el;
	struct vec3 c = dir_of(s->az, s->el);
	double covered = 0;

	if (s->kind == DISC)
		ext_az = fabs(top) >= 89 || fabs(bottom) >= 89
				 ? 180
				 : ext_az / cos(fmax(fabs(top), fabs(bottom)) *
						DEG);
	if (ext_az > 180)
		ext_az = 180;
	int j0 = (int)floor((90 - fmin(top, 90)) / 180 * h);
	int j1 = (int)floor((90 - fmax(bottom, -90)) / 180 * h);
	int i0 = (int)floor((0.5 + (s->az - ext_az) / 360) * w);
	int i1 = (int)floor((0.5 + (s->az + ext_az) / 360) * w);
	if (j1 >= h)
		j1 = h - 1;
	if (i1 - i0 >= w)
		i1 = i0 + w - 1;
	for (int j = j0 < 0 ? 0 : j0; j <= j1; j++)
		for (int ii = i0; ii <= i1; ii++) {
			int i = ((ii % w) + w) % w;
			double cov = 0, cov_cos = 0;
			for (int b = 0; b < k; b++)
				for (int a = 0; a < k; a++) {
					double u = (i + (a + 0.5) / k) / w;
					double v = (j + (b + 0.5) / k) / h;
					double az = (u - 0.5) * 360;
					double el = 90 - v * 180;
					struct vec3 d =
						glint_latlong_uv_to_dir(u, v);
					double p = profile(s, c, az, el, d);
					cov += p;
					cov_cos += p * sin(v * M_PI) *
						   v3_dot(d, c);
				}
			cov /= k * k;
			if (pass == 0) {
				covered += cov_cos / (k * k) * (2 * M_PI / w) *
					   (M_PI / h);
				continue;
			}
			float *px = glint_image_px(img, i, j);
			for (int ch = 0; ch < 3; ch++)
				px[ch] =
					(float)(s->op == OVER
							? px[ch] * (1 - cov) +
								  L[ch] * cov
							: px[ch] + L[ch] * cov);
		}
	return covered;
}

int glint_sim_light_class(const char *name, int width, struct glint_image **out)
{
	const struct light_class *lc = find_class(name);
	struct glint_image *img;

	*out = NULL;
	if (!lc)
		return -EINVAL;
	if (width < 64 || width > 16384 || width % 2)
		return glint_error_set(EINVAL,
				       "light class %s: width %d (an even "
				       "number from 64 to 16384)",
				       name, width);
	img = glint_image_new(width, width / 2);
	if (!img)
		return glint_error_set(ENOMEM, "light class %s: out of memory",
				       name);
	for (int j = 0; j < img->height; j++)
		for (int i = 0; i < width; i++) {
			double rgb[3];
			float *px = glint_image_px(img, i, j);
			lc->background(((i + 0.5) / width - 0.5) * 360,
				       90 - (j + 0.5) / img->height * 180, rgb);
			for (int ch = 0; ch < 3; ch++)
				px[ch] = (float)rgb[ch];
		}
	for (int n = 0; n < lc->nshapes; n++) {
		const struct shape *s = &lc->shapes[n];
		double L[3] = { s->rgb[0], s->rgb[1], s->rgb[2] };
		if (s->op == SMALL) {
			double omega = paint(img, s, L, 0);
			for (int ch = 0; ch < 3; ch++)
				L[ch] = s->rgb[ch] / omega;
		}
		paint(img, s, L, 1);
	}
	*out = img;
	return 0;
}

int glint_sim_light_class_sources(const char *name, struct vec3 *dir,
				  double (*irradiance)[3], int max)
{
	const struct light_class *lc = find_class(name);
	int n = 0;

	if (!lc)
		return -EINVAL;
	for (int k = 0; k < lc->nshapes; k++) {
		const struct shape *s = &lc->shapes[k];
		if (s->op != SMALL)
			continue;
		if (n < max) {
			dir[n] = dir_of(s->az, s->el);
			memcpy(irradiance[n], s->rgb, sizeof(s->rgb));
		}
		n++;
	}
	return n;
}
