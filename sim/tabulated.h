/* SPDX-License-Identifier: MIT */
#ifndef GLINT_SIM_TABULATED_H
#define GLINT_SIM_TABULATED_H

/*
 * Measured (tabulated) isotropic BRDFs for the reference renderer: spheres
 * whose material is none of glint's models.
 *
 * The table is the MERL BRDF database's layout (Matusik et al. 2003): RGB
 * values on 90 x 90 x 180 bins of Rusinkiewicz's half/difference angles,
 * theta_h on a square-root scale (fine near the mirror direction), theta_d
 * and phi_d (0..pi, reciprocity) uniform; the .binary file is three int32
 * dimensions then the red, green and blue planes as doubles, scaled by
 * 1/1500, 1.15/1500 and 1.66/1500 on reading.  Values are looked up in
 * their nearest bin, as the database's own reader does.  Negative values
 * (the database's "not measured") read as 0.
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected.  Threads: a table is read only once built; BxDFs
 * over it may be used from any thread.  Who frees:
 * glint_brdf_table_free().
 */

#include "fit/brdf/model.h"

struct glint_brdf_table;

/* Read a MERL .binary file; the dimensions must be 90 x 90 x 180 and the
 * file exactly their size (the error names what was found). */
int glint_brdf_table_read(const char *path, struct glint_brdf_table **out);
/* Write one, atomically (the database's scaling applied). */
int glint_brdf_table_write(const char *path, const struct glint_brdf_table *t);
void glint_brdf_table_free(struct glint_brdf_table *t);

/* A table sampled from f (RGB per steradian) at each bin's centre. */
int glint_brdf_table_from(void (*f)(void *ctx, struct vec3 wo, struct vec3 wi,
				    double rgb[3]),
			  void *ctx, struct glint_brdf_table **out);

/*
 * Ashikhmin & Shirley (2000), isotropic, as an f for glint_brdf_table_from():
 * a coupled diffuse that falls off toward grazing, a normalised Blinn-Phong
 * lobe of exponent n with Schlick's Fresnel from rs.  None of glint's models:
 * the tests' and benchmarks' material from outside.  ctx is a struct
 * glint_ashikhmin_shirley.
 */
struct glint_ashikhmin_shirley {
	double n, rd[3], rs;
};
void glint_ashikhmin_shirley_eval(void *ctx, struct vec3 wo, struct vec3 wi,
				  double rgb[3]);

/* The table's value for (wo, wi) in the local frame (normal +z). */
void glint_brdf_table_eval(const struct glint_brdf_table *t, struct vec3 wo,
			   struct vec3 wi, double rgb[3]);

/*
 * The table as a BRDF for the reference renderer
 * (glint_reference_render_bxdf()): three lobes, one per channel (lobe c's
 * albedo is the unit vector of channel c, its value the table's channel
 * c), sampled half by the cosine and half by a Beckmann lobe of roughness
 * `proposal` about the mirror direction.  The BxDF's state is *tab, which
 * this fills; tab and t must outlive it.  Any number may coexist.  Not a
 * model: nothing in it is fitted.
 */
struct glint_tabulated {
	const struct glint_brdf_table *table;
	double proposal;
};
struct glint_bxdf glint_tabulated_bxdf(struct glint_tabulated *tab,
				       const struct glint_brdf_table *t,
				       double proposal);

#endif
