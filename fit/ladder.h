/* SPDX-License-Identifier: MIT */
#ifndef GLINT_FIT_LADDER_H
#define GLINT_FIT_LADDER_H

/*
 * The fidelity ladder: model the scene no more finely than the photo can
 * tell.  Each modelling choice (knob) has levels from rich to cheap:
 *   depth of field    the lens's aperture, or a pinhole camera;
 *   samples per pixel primary rays per pixel (8, 4, 1);
 *   image resolution  photo and camera box-averaged by 1, 2, 4;
 *   env-map resolution the map box-averaged by 1, 2, 4;
 *   shading samples   fixed env + lobe samples per hit (16, 8, 4).
 * First a reference fit with every knob at its richest, from which the
 * parameters' standard errors come (s^2 (J^T W J)^-1: the photo's noise
 * and what the model leaves unexplained).  Then, one knob at a time with
 * the others rich, a fit at each cheaper level from the reference
 * parameters; its effect is the largest change of a parameter in units of
 * that parameter's standard error.  A knob takes its cheapest level whose
 * effect is below `threshold`.  Last, a fit with every chosen level from
 * the usual start checks the combination: if it moves a parameter by a
 * standard error or more, the knob with the largest effect steps back up
 * one level, and again.
 * Two more choices are decided without fits and reported: bounce depth
 * (a lone convex opaque sphere sees only the map: one bounce is exact) and
 * the sample's stand (not modelled: the scene has no geometry for it).
 * Opaque models only; the transparent fitter has its own path depth.
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected.  Threads: runs its own worker threads (nthreads).
 * Who frees: json_decref() a document out.
 */

#include "fit.h"

#include <jansson.h>

enum {
	GLINT_LADDER_DOF,
	GLINT_LADDER_SPP,
	GLINT_LADDER_RES,
	GLINT_LADDER_ENV,
	GLINT_LADDER_SAMPLES,
	GLINT_LADDER_NKNOBS
};

#define GLINT_LADDER_MAX_LEVELS 4

/* One setting of every knob. */
struct glint_ladder_setting {
	int dof;	/* model the scene's aperture (else a pinhole) */
	int spp;	/* primary samples per pixel */
	int res_factor; /* photo and camera box-averaged by this */
	int env_factor; /* env map box-averaged by this */
	int samples;	/* fixed env and lobe samples per hit, each */
};

struct glint_ladder_level {
	int value;	/* the knob's value at this level */
	double effect;	/* largest |dp| / se against the reference fit */
	int param;	/* the parameter that moved most (-1: none) */
	double seconds; /* that fit, set-up included */
	int tried;
};

struct glint_ladder_knob {
	const char *name;
	int nlevels; /* level 0 is the reference */
	struct glint_ladder_level level[GLINT_LADDER_MAX_LEVELS];
	int chosen;
	char why[200];
};

struct glint_ladder_result {
	struct glint_ladder_setting reference, chosen;
	struct glint_ladder_knob knob[GLINT_LADDER_NKNOBS];
	struct glint_fit_result ref_fit, chosen_fit;
	double ref_seconds, chosen_seconds;
	/* largest |dp| / se of the chosen fit against the reference one,
	 * and which parameter */
	double final_effect;
	int final_param;
	int backoffs; /* knobs stepped back up to get it below 1 */
	double threshold;
};

/*
 * Run the ladder for `model` on `photo` (weight may be NULL) in `scene`.
 * base gives the fit's method and other options (its max_pixels, sample
 * counts and progress are overridden).  threshold: the largest effect a
 * knob's level may have, in standard errors (0.5 is a good choice: the
 * knobs' effects add up).  knobs: which to try (bit 1 << GLINT_LADDER_*;
 * 0 for all); the others stay as scene and base have them.  The chosen
 * setting's fit ends in out->chosen_fit.
 */
int glint_ladder_run(const struct glint_scene *scene,
		     const struct glint_model *model,
		     const struct glint_image *photo,
		     const struct glint_image *weight,
		     const struct glint_fit_opts *base, double threshold,
		     unsigned knobs, int nthreads,
		     struct glint_ladder_result *out);

/* "dof,spp,resolution,env,samples" (any of them) to a knob mask. */
int glint_ladder_knobs_parse(const char *list, unsigned *knobs);

/* Apply a setting to a scene (camera, spp) and fit options (samples). */
void glint_ladder_apply(const struct glint_ladder_setting *s,
			struct glint_scene *scene, struct glint_fit_opts *o);

/* The report as JSON (what was chosen and why, every level's effect and
 * time); caller json_decref()s. */
json_t *glint_ladder_to_json(const struct glint_ladder_result *r);

/* A line per knob for people. */
void glint_ladder_print(const struct glint_ladder_result *r, FILE *f);

#endif
