/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CAPTURE_PROBE_PROBE_SOURCES_H
#define GLINT_CAPTURE_PROBE_PROBE_SOURCES_H

/*
 * Light sources the probe cannot resolve.  A lamp or the sun that covers
 * a pixel or two of the mirror ball is smeared by the lens, the optical
 * low-pass filter and the demosaic over a patch of the photo, and the
 * unwrap turns that patch into a blob degrees wide: its flux is right, its
 * shape is the camera's, and a glossy sphere's highlight under the blob is
 * broader and dimmer than the one the sphere saw.  glint finds such
 * sources in the merged probe photo (a peak many times its surroundings
 * whose light lies within a 2-pixel radius), measures each one's flux
 * (radiance x solid angle, divided by the ball's reflectance, over a
 * 4-pixel aperture less the background fitted as a plane to the ring
 * around it, both up to 89 degrees of incidence: a lamp behind the
 * sample lies near the ball's rim, past the map's grazing limit), its
 * direction (the flux-weighted mean of the directions the
 * aperture's pixels reflect) and their uncertainties, takes it out of the
 * photo (the background in its place) before the unwrap and puts it back
 * into the map as a point: its flux in the texels around its direction
 * (bilinear weights), so that the map's total light is unchanged and the
 * light is as concentrated as the map allows.  A source clipped in the
 * merge (a weight of 0 in the aperture: saturated in the shortest frame)
 * is kept and marked: its flux is a lower bound, and its concentration
 * is not judged (a clipped core holds less than its share), only its
 * contrast against the ring.  A gray ball's photo measures such a
 * source's flux and direction (capture/probe/probe_calibrate.h).
 *
 * Uncertainties (1 sigma): flux from the photo's variance over the
 * aperture, the background (the plane's own error, and the sky's
 * structure the plane leaves in the ring, its RMS, taken as half
 * correlated across the aperture) and the aperture's convergence (the
 * flux within 3 against within 4 pixels); direction from
 * a quarter pixel of centroid error in the photo (a mosaic-sampled spot)
 * plus the centroid's noise, as the angle those pixels reflect.
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected.  Threads: re-entrant.  Who frees: images out with
 * glint_image_free(); a glint_light_sources is the caller's (fixed size).
 */

#include "capture/probe/probe.h"

#define GLINT_MAX_SOURCES 16

struct glint_light_source {
	struct vec3 dir;	 /* unit, in the map's frame */
	double dir_sigma_deg;	 /* its 1-sigma angular uncertainty */
	double flux[3];		 /* integral of L d(omega), per channel */
	double flux_sigma[3];	 /* 1 sigma */
	double size_deg;	 /* RMS angular radius as photographed */
	double photo_x, photo_y; /* its centroid in the photo, px */
	double px_deg;		 /* the angle a photo pixel spans there */
	double contrast;	 /* peak over the background (luminance) */
	int saturated;		 /* clipped: flux is a lower bound */
};

struct glint_light_sources {
	int n;
	struct glint_light_source s[GLINT_MAX_SOURCES];
	/* the whole map's integral of L d(omega) (after the unwrap) */
	double total_flux[3];
	/* The angle one probe pixel spans at 90 degrees from the probe
	 * camera's axis (2 sqrt 2 / ball radius, in degrees): how finely the
	 * map unwrapped from this probe resolves the light, which sizes the
	 * fit's systematic roughness term (fit/discrepancy.c).  0: not known
	 * (a file written without it). */
	double map_pixel_deg;
};

/* Detection thresholds (defaults: contrast 8, 70 % of the light within 2
 * px, each source at least 0.2 % of the probe's light). */
struct glint_source_opts {
	double min_contrast;
	double min_concentration;
	double min_share;
};

void glint_source_default_opts(struct glint_source_opts *o);

/*
 * The compact sources on the ball of `photo` (ball and camera in o, as for
 * glint_probe_unwrap).  variance and weights (the merge's, same size; may
 * be NULL) give the flux's noise and the clipped pixels.  *cleaned (may be
 * NULL) gets a copy of the photo with each source's aperture replaced by
 * its background.  out->total_flux is left 0 (glint_probe_add_sources
 * sets it).
 */
int glint_probe_find_sources(const struct glint_image *photo,
			     const struct glint_image *variance,
			     const struct glint_image *weights,
			     const struct glint_unwrap_opts *o,
			     const struct glint_source_opts *so,
			     struct glint_light_sources *out,
			     struct glint_image **cleaned);

/* Each source's flux into the lat-long map env at its direction (the
 * four nearest texels, bilinear weights, divided by their solid angle);
 * then s->total_flux = the map's integral of L d(omega). */
void glint_probe_add_sources(struct glint_image *env,
			     struct glint_light_sources *s);

/* The map's integral of L d(omega), per channel. */
void glint_latlong_flux(const struct glint_image *env, double flux[3]);

/*
 * The sources as JSON (atomically), for people and for the fit: per
 * source its direction (unit vector, and azimuth/elevation in degrees in
 * the map's convention), flux and colour (flux / its mean), each with its
 * sigma, its share of the map's light, size, place in the photo and
 * whether it is clipped.  `photo` names the photo it came from.
 */
int glint_probe_sources_write(const char *path, const char *photo,
			      const struct glint_light_sources *s);

/* Read what glint_probe_sources_write wrote; -ENOENT when there is no
 * file (a map unwrapped without sources), else an error naming the file
 * and the key. */
int glint_probe_sources_read(const char *path, struct glint_light_sources *s);

#endif
