/* SPDX-License-Identifier: MIT */
#ifndef GLINT_FIT_JOB_H
#define GLINT_FIT_JOB_H

/*
 * One fit as `glint fit`, `glint demo` and the queue run it, and the
 * result folder it writes (docs/scene.md, "params.json").
 *
 * Errors: a negative errno with glint_error_msg() naming the file or value
 * and what was expected; a failed stage stops the job, named, and nothing
 * partial is left as a result.  Threads: called from one thread; it runs
 * its own worker threads.  Who frees: glint_fit_job_unload() a loaded
 * job's images; json_decref() a result document.
 */

#include "fit.h"

#include <jansson.h>

struct glint_fit_job {
	const char *scene_path; /* for the record and messages */
	const char *photo_path;
	const char *weights_path; /* set by glint_fit_job_load(); may be NULL */
	int srgb; /* the photo is 8-bit sRGB, to be linearised (--srgb) */
	struct glint_scene scene;
	const struct glint_model *model; /* NULL: --model auto */
	struct glint_image *photo;	 /* owned by the caller */
	struct glint_image *weight;	 /* may be NULL */
	/* opts.progress (may be NULL) is called as passes run, and once
	 * with pass NULL when they are done */
	struct glint_fit_opts opts;
	const char *out_dir;
	/* NULL, or the name params.json gives the working folder: paths
	 * that begin with "./" are recorded beneath it (a queue worker's
	 * fit runs beneath its session's descriptor, named "."). */
	const char *shown_dir;
	int nthreads;
	/* the final render's time budget in seconds; 0: half the fit's
	 * time and at least 1 s.  The render's sample counts, and so its
	 * pixels and the misfit, depend on the machine's speed within a
	 * budget; a large one (1e9) makes them depend on the photo alone. */
	double render_budget_s;
	/* the scene's light sources (environment.sources), read by
	 * glint_fit_job_load() */
	struct glint_fit_light_source sources[GLINT_FIT_MAX_SOURCES];
	int nsources;
	/* the probe's resolution from the sources file (its map_pixel_deg;
	 * -1 where the file does not say); 0 without a sources file: the
	 * map is taken as the light itself */
	double map_pixel_deg;
	/* > 0: run the fidelity ladder (fit/ladder.h) with this limit in
	 * standard errors and report its fit */
	double ladder;
	unsigned ladder_knobs; /* 0: all */
	/* choose among the opaque models by BIC (fit/select.h); without it
	 * the choice is made anyway when the fit leaves a parameter
	 * undetermined, unless no_auto_select */
	int select;
	int no_auto_select;
	/* > 0: accept a fit whose relative RMSE is below this instead of
	 * the default rule (glint_fit_judge) */
	double accept_rmse;
	/* write into out_dir even when it holds files glint did not
	 * write: glint's own are replaced, the others kept (never an input
	 * of this run, never a file of someone else's of a name it writes) */
	int force;
	/* replace a previous result (a folder of glint's files alone) in
	 * out_dir; without it one is refused (the one overwrite rule,
	 * core/output.h) */
	int replace;
	/* The material's name in params.json and the exports; NULL:
	 * from out_dir (glint_export_name_from_path: a session's fit is
	 * named after the session). */
	const char *name;
	/* bit k set: write out_dir/material + the extension of export
	 * format k (export/export.h) with an accepted result */
	unsigned exports;
	/* More photos of the same material, each in its own scene: one
	 * fit to all of them (glint_fit_views()).  Each is a job of its own
	 * of which only the inputs are used (scene_path, photo_path, loaded
	 * by glint_fit_job_load() and _crop()); this job has the options
	 * and the output.  The others' renders and compare images go into
	 * out_dir as render-N.exr and compare-N.png (N = 2, 3, ...), their
	 * statistics into params.json's "photos". */
	struct glint_fit_job *also;
	int nalso;
	/* With more photos: unless no_per_light, each also fitted alone and
	 * each parameter's drift with the light's angle reported
	 * (fit/per_light.h; params.json's "per_light"). */
	int no_per_light;
	/* Set by glint_fit_job_crop() or _load(): the photo, weights and
	 * camera are
	 * the window at (x, y) of a frame_width x frame_height frame
	 * (frame_width 0: the whole frame). */
	struct {
		int x, y, frame_width, frame_height;
	} window;
};

/*
 * Read the job's inputs: the scene from scene_path, the photo from
 * photo_path and, when weights_path is not NULL, the per-pixel weights.
 * When the photo (and the weights) are the camera's frame and the
 * sphere's window saves a quarter of it (glint_fit_job_crop()), only the
 * window is read (an EXR decodes only the chunks it touches: a 12 MP
 * photo is never held whole) and the job is narrowed to it as
 * glint_fit_job_crop() does.  The images are the job's until
 * glint_fit_job_unload(), which is safe after a failed load too.
 */
int glint_fit_job_load(struct glint_fit_job *job, const char *weights_path);
void glint_fit_job_unload(struct glint_fit_job *job);

/*
 * Narrow the job to the sphere: the rectangle around the scene sphere's
 * silhouette plus a margin (a tenth of its radius and 8 pixels, and the
 * lens blur), when that saves at least a quarter of the frame.  The photo
 * and weights (the job's, freed and replaced) become that window, the
 * camera is shifted to it, job->window says where it lies; the fit, the
 * final render and compare.png then cover the window only, and
 * render.exr keeps the frame as its display window.  The fit's pixels
 * all lie on the sphere, so its answer does not depend on the window.
 * A photo that is not the camera's size is left alone (the fit says
 * so).  Returns 0, or -ENOMEM.
 */
int glint_fit_job_crop(struct glint_fit_job *job);

/*
 * Trace, fit, render the result and write out_dir/{params.json,
 * render.exr, compare.png} (and the material in each format of
 * job->exports, refitted: params.json's "exports" lists each file with
 * its refit's residual, or why there is none) as one atomic folder.  Before any
 * work, an out_dir (or its ".refused" sibling) that holds anything but a
 * previous result is refused unless force, and the current folder always
 * (glint_atomic_dir_check).  A fit that
 * glint_fit_judge() refuses fails with -EINVAL and the reason; its
 * diagnostics (the same three files, params.json with "accepted": false)
 * go to the sibling folder out_dir + ".refused", and out_dir is left as
 * it was.  *result is the params.json document plus
 * "output" (the caller json_decref()s it).
 */
int glint_fit_job_run(const struct glint_fit_job *job, json_t **result);

/*
 * The final render's second pair of renders (fit/job.c): given the first
 * pair's noise q1 in the photo's variance units and its time pair_s, the
 * factor on the scene's samples that brings the combined noise to the
 * target, at most 4 and affordable within budget_s (0: no second pair).
 * *limited_by names what held it below the target, else NULL.
 */
int glint_render_factor(double q1, double pair_s, double budget_s,
			const char **limited_by);

/*
 * The first pair's samples, as a factor on the scene's, from a pilot
 * (every 16th row) whose pair's noise is q_pilot and whose full-size pair
 * would take pair_s: no more than half the noise target needs (q falls
 * as 1 / samples) and no more than budget_s affords, at most 1 and at least
 * 1/8.  *limited_by says "time" when the budget cut it, else NULL.
 */
double glint_render_first_factor(double q_pilot, double pair_s, double budget_s,
				 const char **limited_by);

/*
 * The pixel step of the final render (glint_shade_opts.pixel_step): 1 when
 * a pair at `factor` of the scene's samples, pair_s at factor 1 over every
 * pixel, fits budget_s; else the step k whose grid (a k-th of the rows
 * and of the columns: 1/k^2 of the shading) does, at most 8 (8 when
 * nothing is left of the budget).
 */
int glint_render_pixel_step(double factor, double pair_s, double budget_s);

/* Parameter k is not determined: its interval spans half its bounds or
 * more, or the photo cannot see it at all. */
int glint_fit_undetermined(const struct glint_fit_result *r, int k);

/* params.json's "parameters" (name, value, stderr, at_bound, bounds) and
 * "passes" arrays for a result; new references. */
json_t *glint_fit_params_json(const struct glint_fit_result *r);
json_t *glint_fit_passes_json(const struct glint_fit_result *r);

/* params.json's "uncertainty": how the intervals were made, the
 * covariance and correlation, and findings: parameters the photo does
 * not determine, trade-offs (with the combination it does determine),
 * roughness below the pixel footprint.  JSON null when the fitter gave
 * no covariance (transparent models).  A new reference. */
json_t *glint_fit_uncertainty_json(const struct glint_fit_result *r);

/*
 * Whether a fit is taken as a measurement, by a stated rule: its relative
 * RMSE must be below both the bare backdrop's (else the photo shows the
 * backdrop where the scene puts the sphere) and a flat disc's of the
 * photo's mean colour (else it shows something else); or, when
 * accept_rmse > 0, below that.  An accepted fit gets a misfit verdict:
 * its residual against what noise alone leaves.
 */
struct glint_fit_verdict {
	int accepted;
	double limit; /* the relative RMSE the fit had to stay below */
	double ratio; /* rmse / noise_rmse (NAN without a noise model) */
	char rule[160];
	char verdict[320];
};

/* A joint fit's result as photo k alone sees it (its pixels, RMSE and
 * baselines: res->view[k]; nviews 1), to judge that photo by. */
void glint_fit_result_view(const struct glint_fit_result *res, int k,
			   struct glint_fit_result *out);

/* Fill v; returns v->accepted. */
int glint_fit_judge(const struct glint_fit_result *r, double accept_rmse,
		    struct glint_fit_verdict *v);

/* params.json's "acceptance" (a new reference). */
json_t *glint_fit_verdict_json(const struct glint_fit_result *r,
			       const struct glint_fit_verdict *v);

/* Does the photo leave a parameter of r undetermined, or specular and ior
 * trading off (|correlation| >= 0.95 without the shared systematic
 * source: glint_uncertainty_corr_without_shared())?  Then
 * glint_fit_job_run() chooses the model by BIC as --select-model does. */
int glint_fit_needs_selection(const struct glint_fit_result *r);

/* Specular x F0(ior) of r per channel (NAN where the model has no such
 * channel), its delta-method standard error, and the largest |correlation|
 * of a specular channel with ior in corr.  Returns 1 when the photo
 * determines that product rather than each (they correlate beyond 0.9, or
 * ior is not determined), 0 when it determines each, -1 when the model
 * has no ior (nothing filled). */
int glint_fit_specular_f0(const struct glint_fit_result *r, double v[3],
			  double se[3], double *corr);

/* A path as params.json records it: beneath job->shown_dir when it
 * begins with "./" (a new reference). */
json_t *glint_fit_job_shown_path(const struct glint_fit_job *job,
				 const char *path);

#endif
