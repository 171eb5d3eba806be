/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CORE_OPTICS_H
#define GLINT_CORE_OPTICS_H

/*
 * Geometric optics at a smooth interface: Fresnel reflectance (dielectric
 * and conductor, unpolarised) and the reflected and refracted directions.
 * The models (fit/brdf/), the transparent sphere's paths
 * (fit/render/dielectric_paths.c) and the probe's chrome ball
 * (capture/probe/probe.c) use these; the reference renderer (sim/) keeps
 * its own, independently written forms on purpose.
 *
 * Pure functions: no errors, no allocation, safe from any thread.
 *
 * Errors: none (pure functions).  Threads: re-entrant.  Who frees:
 * nothing.
 */

#include "core/vec.h"

/*
 * Exact Fresnel reflectance of unpolarised light at a smooth dielectric
 * interface of relative index n >= 1, incidence from the outside at angle
 * with cosine c (Cook & Torrance 1982, eq. 8; equals (Rs + Rp) / 2).
 */
double glint_fresnel_dielectric(double c, double n);
/* The same reflectance, and in *dlog d F / d n over F: how a change of
 * index scales it (0 where F is 0: at n = 1, or beyond the critical
 * angle), sharing their square root. */
double glint_fresnel_dielectric_dlog(double c, double n, double *dlog);

/* The same reflectance from the incident side of either orientation:
 * cos_i > 0 the cosine of incidence, eta = n_transmitted / n_incident.
 * 1 beyond the critical angle.  *cos_t (may be NULL) gets the cosine of
 * the refracted ray (0 on total internal reflection).  The two forms
 * agree to rounding; each caller keeps the one its results were
 * measured with. */
double glint_fresnel_interface(double cos_i, double eta, double *cos_t);

/* Fresnel reflectance of a conductor of complex index n + ik at
 * cos(incidence) c (clamped to [0, 1]). */
double glint_fresnel_conductor(double n, double k, double c);

/* Directions at an interface with unit normal n facing the incident unit
 * direction d (dot(d, n) < 0): the mirror direction, and the refracted one
 * for eta = n_t / n_i (returns 0 on total internal reflection). */
struct vec3 glint_reflect(struct vec3 d, struct vec3 n);
int glint_refract(struct vec3 d, struct vec3 n, double eta, struct vec3 *t);

#endif
