/* SPDX-License-Identifier: MIT */
#ifndef GLINT_FIT_BRDF_MICROFACET_H
#define GLINT_FIT_BRDF_MICROFACET_H

/* Pieces of the Torrance-Sparrow model, exposed for tests. */

/*
 * Beckmann distribution of microfacet normals with RMS slope m:
 * D(h) = exp(-tan^2(t) / m^2) / (pi m^2 cos^4(t)), t the angle between h
 * and the normal; integral of D(h) cos(t) over the hemisphere is 1.
 */
double glint_beckmann_d(double cos_h, double m);

/*
 * Exact Fresnel reflectance of unpolarised light at a smooth dielectric
 * interface of relative index n >= 1, incidence from the outside at angle
 * with cosine c (Cook & Torrance 1982, eq. 8; equals (Rs + Rp) / 2).
 */
double glint_fresnel_dielectric(double c, double n);

/*
 * Torrance-Sparrow V-cavity shadowing and masking:
 * G = min(1, 2 (n.h)(n.o) / (o.h), 2 (n.h)(n.i) / (o.h)).
 */
double glint_vcavity_g(double nh, double no, double ni, double oh);

#endif
