/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CAPTURE_PROBE_PROBE_H
#define GLINT_CAPTURE_PROBE_PROBE_H

/*
 * Light probes: the four formats seen in the wild, conversions between
 * them, and unwrapping a photographed mirror ball with the rig's
 * perspective camera.  Orientation (docs/hdr.md): +Y up, the lat-long
 * centre and the angular map's centre look along -Z; directions are in the
 * map's frame (for an unwrapped ball: the camera's frame, x right, y up,
 * the camera looking along -Z).
 *
 *   latlong  2:1, u = 0.5 + atan2(x, -z) / 2pi across, v = acos(y) / pi
 *            down (docs/conventions.md)
 *   angular  square; a direction at angle theta from -Z sits at radius
 *            theta / pi of the half-width, towards (x, y) (Debevec's
 *            "light probe" format: -Z at the centre, +Z on the rim)
 *   cross    vertical cube cross, 3 x 4 faces of side s:
 *                  . +Y .        +Y seen from inside, -Z edge at bottom
 *                 -X -Z +X       the horizontal band, as looking around
 *                  . -Y .
 *                  . +Z .        the back face upside down (HDR Shop)
 *   ball     an ideal mirror ball seen orthographically from +Z (the
 *            "mirrored ball" format): pixel (u, v) in the unit disk has
 *            normal (u, v, sqrt(1 - u^2 - v^2)) and shows the reflection
 *            of the view direction -Z
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected.  Threads: re-entrant; names are static strings.
 * Who frees: images out with glint_image_free().
 */

#include "core/image.h"
#include "core/vec.h"

enum glint_probe_format {
	GLINT_PROBE_LATLONG,
	GLINT_PROBE_ANGULAR,
	GLINT_PROBE_CROSS,
	GLINT_PROBE_BALL,
};

/* "latlong", "angular", "cross", "ball"; -EINVAL naming the choices. */
int glint_probe_format_parse(const char *name, enum glint_probe_format *f);
/* The name of f: a static string. */
const char *glint_probe_format_name(enum glint_probe_format f);

/* The direction seen at continuous pixel (x, y) of a w x h image; 0 when
 * the pixel shows none (outside the disk or the cross). */
int glint_probe_pixel_dir(enum glint_probe_format f, int w, int h, double x,
			  double y, struct vec3 *d);

/* Where direction d (unit) is, in continuous pixels. */
void glint_probe_dir_pixel(enum glint_probe_format f, int w, int h,
			   struct vec3 d, double *x, double *y);

/* Radiance along d from an image in format f (bilinear; inside the face
 * for the cross). */
void glint_probe_lookup(const struct glint_image *img,
			enum glint_probe_format f, struct vec3 d, float rgb[3]);

/* Resample src (format `from`) into format `to`, w x h (0: a size with
 * about the source's resolution), 2 x 2 samples per pixel.  *out is the
 * caller's, freed with glint_image_free(). */
int glint_probe_convert(const struct glint_image *src,
			enum glint_probe_format from,
			enum glint_probe_format to, int w, int h,
			struct glint_image **out);

/* A photographed mirror ball. */
struct glint_unwrap_opts {
	double fpx;    /* camera focal length, pixels */
	double cx, cy; /* principal point, pixels (-1: centre) */
	double ball_cx, ball_cy, ball_r; /* the ball's image circle, px */
	/* Reflectance: complex index of refraction per channel (Fresnel for
	 * a conductor), or `reflectivity` > 0 for a constant one. */
	double n[3], k[3];
	double reflectivity;
	double grazing_deg;	/* unreliable beyond this angle of incidence
				   (default 80) */
	double camera_cone_deg; /* the camera's own reflection (default 6) */
	/* The camera's blur (a scene's camera.psf_sigma_px and olpf): the
	 * ball's pixels within 3 of its standard deviations of the rim mix
	 * with what lies beside the ball, and are unreliable. */
	double psf_sigma_px;
	int olpf;
	/* 0 (default): the directions behind the ball that the photo does
	 * not show reliably (grazing, or on the blurred rim) are filled by
	 * a harmonic interpolation from the reliable ones around them; 1:
	 * left as photographed. */
	int no_fill;
	int orthographic;  /* for comparison: the approximation peers
			      use (parallel view rays) */
	int width, height; /* lat-long output (default 4 r x 2 r) */
	/* Compact light sources (capture/probe/probe_sources.h): found and
	 * put into the map as points unless no_sources; the merge's
	 * variance and weights (may be NULL) give their noise and say which
	 * are clipped. */
	int no_sources;
	const struct glint_image *variance, *weights;
};

/* Defaults: chrome (n 3.2, k 3.3: 55 % at normal incidence), 80 deg, 6 deg,
 * perspective. */
void glint_unwrap_default_opts(struct glint_unwrap_opts *o);

/* How far inside the rim, in pixels, the camera's blur reaches: 3
 * standard deviations of the lens and demosaic (psf_sigma_px), the OLPF's
 * split (0.5 px) and the pixel's square (1 / sqrt(12) px) together. */
double glint_unwrap_rim_margin_px(const struct glint_unwrap_opts *o);

/*
 * Lat-long radiance in the camera's frame, divided by the ball's
 * reflectance at each point's angle of incidence; mask 1 where reliable
 * (not grazing, not within glint_unwrap_rim_margin_px() of the rim, not
 * the camera's reflection, inside the photo), else 0; unless o->no_fill,
 * the unreliable directions behind the ball interpolated from around them;
 * density = photo pixels per steradian (for blending views).  mask and
 * density may be NULL; the images are the caller's, freed with
 * glint_image_free().
 */
int glint_probe_unwrap(const struct glint_image *photo,
		       const struct glint_unwrap_opts *o,
		       struct glint_image **env, struct glint_image **mask,
		       struct glint_image **density);

/*
 * Unwrap and write the map to env_path, its reliability mask to
 * ENV-mask.png, its sampling density to ENV-density.exr and its compact
 * light sources to ENV-sources.json beside it (ENV: env_path without its
 * extension; no sources file with o->no_sources), each atomically.
 * *width, *height (may be NULL) get the map's size.
 */
int glint_probe_unwrap_write(const struct glint_image *photo,
			     const struct glint_unwrap_opts *o,
			     const char *env_path, int *width, int *height);

/*
 * The ball's circle in o->ball_cx, ball_cy, ball_r: found by the sphere
 * detector (capture/probe/sphere_detect.h) unless `given`; a given circle is
 * kept, with a warning when the detector finds one more than 2 px away.
 */
int glint_probe_find_ball(const struct glint_image *photo, int given,
			  struct glint_unwrap_opts *o);

#endif
