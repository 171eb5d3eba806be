/* SPDX-License-Identifier: MIT */
/* The fidelity ladder (ladder.h). */
#define _POSIX_C_SOURCE 200809L
#include "ladder.h"

#include "core/clock.h"
#include "core/error.h"
#include "core/log.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static const char *const knob_names[GLINT_LADDER_NKNOBS] = {
	"depth of field",     "samples per pixel", "image resolution",
	"env-map resolution", "shading samples",
};

struct ladder {
	struct glint_scene scene;
	const struct glint_model *model;
	const struct glint_image *photo, *weight;
	struct glint_fit_opts base;
	int nthreads;
	struct glint_image *env_img; /* the full map, read once */
	/* photo and weight box-averaged by 1, 2, 4 (index log2) */
	struct glint_image *photos[3], *weights[3];
};

/* The setting's value of knob k. */
static int *knob_value(struct glint_ladder_setting *s, int k)
{
	switch (k) {
	case GLINT_LADDER_DOF:
		return &s->dof;
	case GLINT_LADDER_SPP:
		return &s->spp;
	case GLINT_LADDER_RES:
		return &s->res_factor;
	case GLINT_LADDER_ENV:
		return &s->env_factor;
	default:
		return &s->samples;
	}
}

void glint_ladder_apply(const struct glint_ladder_setting *s,
			struct glint_scene *scene, struct glint_fit_opts *o)
{
	struct glint_pinhole *c = &scene->cam;
	if (!s->dof)
		c->aperture_radius = 0;
	scene->spp = s->spp;
	if (s->res_factor > 1) {
		int f = s->res_factor;
		c->width /= f;
		c->height /= f;
		c->fpx /= f;
		c->cx /= f;
		c->cy /= f;
	}
	o->light_samples = o->lobe_samples = s->samples;
}

/* Inverse-variance weights of a box average: the mean of f^2 pixels has
 * variance sum(1 / w) / f^4; one unusable pixel (weight 0) spoils it. */
static struct glint_image *downsample_weight(const struct glint_image *w, int f)
{
	struct glint_image *d = glint_image_new(w->width / f, w->height / f);
	for (int y = 0; d && y < d->height; y++)
		for (int x = 0; x < d->width; x++)
			for (int c = 0; c < 3; c++) {
				double var = 0;
				int bad = 0;
				for (int j = 0; j < f; j++)
					for (int i = 0; i < f; i++) {
						double v = glint_image_px(
							w, f * x + i,
							f * y + j)[c];
						bad |= !(v > 0) || !isfinite(v);
						var += 1 / v;
					}
				glint_image_px(d, x, y)[c] =
					bad ? 0 : (float)(f * f * f * f / var);
			}
	return d;
}

static int level_index(int f)
{
	return f == 1 ? 0 : f == 2 ? 1 : 2;
}

static int photo_at(struct ladder *l, int f, const struct glint_image **photo,
		    const struct glint_image **weight)
{
	int i = level_index(f);
	if (!l->photos[i]) {
		l->photos[i] = glint_image_downsample(l->photo, f);
		if (l->weight)
			l->weights[i] = downsample_weight(l->weight, f);
		if (!l->photos[i] || (l->weight && !l->weights[i]))
			return glint_error_set(ENOMEM, "out of memory");
	}
	*photo = l->photos[i];
	*weight = l->weights[i];
	return 0;
}

/* Fit at setting s from start; *seconds: the whole of it (map, trace,
 * fit). */
static int fit_at(struct ladder *l, const struct glint_ladder_setting *s,
		  const double *start, struct glint_fit_result *res,
		  double *seconds)
{
	struct glint_scene sc = l->scene;
	struct glint_fit_opts o = l->base;
	struct glint_renderer r;
	struct glint_envmap *env;
	const struct glint_image *photo = NULL, *weight = NULL;
	char what[64];
	double t0 = glint_clock_monotonic();

	glint_ladder_apply(s, &sc, &o);
	/* Every pixel on the sphere up to 16384 (a 512 px photo: every
	 * second row and column): rich, and not minutes per fit. */
	o.max_pixels = o.max_pixels > 16384 ? o.max_pixels : 16384;
	o.start = start;
	/* Knobs are judged against the photo's noise: one fixed sample set
	 * per fit, standard errors from the noise part alone (the polish on
	 * several sets moves each fit by its own Monte Carlo draw, which is
	 * the fitter's, not the scene model's). */
	o.mc_draws = 0;
	o.progress = NULL;
	o.nthreads = l->nthreads;
	int ret = photo_at(l, s->res_factor, &photo, &weight);
	if (ret < 0)
		return ret;
	struct glint_image *img =
		s->env_factor > 1
			? glint_image_downsample(l->env_img, s->env_factor)
			: glint_image_dup(l->env_img);
	if (!img)
		return glint_error_set(ENOMEM, "out of memory");
	glint_text(what, sizeof(what), "%s (box-averaged by %d)", sc.env_path,
		   s->env_factor);
	ret = glint_envmap_new(img, sc.env_rotation, sc.env_scale, what, &env);
	if (ret < 0)
		return ret;
	ret = glint_renderer_init_env(&r, &sc, env, l->nthreads, NULL);
	if (ret < 0)
		return ret;
	ret = glint_fit(&r, l->model, photo, weight, &o, res);
	glint_renderer_release(&r);
	*seconds = glint_clock_monotonic() - t0;
	return ret;
}

/* Largest |p - ref| over the parameters, in units of the reference fit's
 * standard errors (the cheaper fit's where the reference has none, a
 * parameter on its bound); *which gets the parameter. */
static double effect_of(const struct glint_fit_result *p,
			const struct glint_fit_result *ref, int *which)
{
	double e = 0;
	int nparams = ref->model->nparams;
	*which = -1;
	for (int k = 0; k < nparams; k++) {
		double se = ref->se[k];
		if (!(se > 0) || !isfinite(se))
			se = p->se[k];
		if (!(se > 0) || !isfinite(se))
			continue;
		double z = fabs(p->p[k] - ref->p[k]) / se;
		if (z > e) {
			e = z;
			*which = k;
		}
	}
	return e;
}

static void set_levels(struct ladder *l, struct glint_ladder_result *out)
{
	static const int spp[] = { 8, 4, 1 }, res[] = { 1, 2, 4 },
			 samples[] = { 16, 8, 4 };
	const struct glint_pinhole *c = &l->scene.cam;
	struct vec3 d = v3_sub(l->scene.sphere_centre, c->pos);
	double radius_px = c->fpx * l->scene.sphere_radius / v3_len(d);

	for (int k = 0; k < GLINT_LADDER_NKNOBS; k++) {
		struct glint_ladder_knob *kn = &out->knob[k];
		memset(kn, 0, sizeof(*kn));
		kn->name = knob_names[k];
	}
	struct glint_ladder_knob *kn = &out->knob[GLINT_LADDER_DOF];
	kn->level[kn->nlevels++].value = c->aperture_radius > 0;
	if (c->aperture_radius > 0)
		kn->level[kn->nlevels++].value = 0;
	else
		snprintf(kn->why, sizeof(kn->why),
			 "the scene's camera is a pinhole (no f_number)");
	kn = &out->knob[GLINT_LADDER_SPP];
	for (int i = 0; i < 3; i++)
		kn->level[kn->nlevels++].value = spp[i];
	kn = &out->knob[GLINT_LADDER_RES];
	/* A sphere under about 12 px in radius leaves too few pixels. */
	for (int i = 0; i < 3; i++)
		if (i == 0 || radius_px / res[i] >= 12)
			kn->level[kn->nlevels++].value = res[i];
	kn = &out->knob[GLINT_LADDER_ENV];
	for (int i = 0; i < 3; i++)
		if (i == 0 || l->env_img->height / res[i] >= 16)
			kn->level[kn->nlevels++].value = res[i];
	kn = &out->knob[GLINT_LADDER_SAMPLES];
	for (int i = 0; i < 3; i++)
		kn->level[kn->nlevels++].value = samples[i];
	for (int k = 0; k < GLINT_LADDER_NKNOBS; k++)
		*knob_value(&out->reference, k) = out->knob[k].level[0].value;
}

static const char *param_name(const struct glint_model *m, int k)
{
	return k >= 0 ? m->params[k].name : "nothing";
}

static void explain(struct glint_ladder_knob *kn,
		    const struct glint_model *model, double threshold)
{
	if (kn->nlevels < 2)
		return;
	struct glint_ladder_level *c = &kn->level[kn->chosen];
	if (kn->chosen == 0) {
		/* the cheapest level tried says most */
		struct glint_ladder_level *n = &kn->level[1];
		snprintf(kn->why, sizeof(kn->why),
			 "kept: %d moves %s by %.2f standard errors (limit "
			 "%.2f)",
			 n->value, param_name(model, n->param), n->effect,
			 threshold);
	} else
		snprintf(kn->why, sizeof(kn->why),
			 "%d moves the fit by %.2f standard errors at most "
			 "(limit %.2f); %.2f s there, %.2f s at %d",
			 c->value, c->effect, threshold, c->seconds,
			 kn->level[0].seconds, kn->level[0].value);
}

/* Knobs not tried stay as the scene and options have them. */
static void untried(struct glint_ladder_result *out,
		    const struct glint_scene *scene,
		    const struct glint_fit_opts *base, unsigned knobs)
{
	struct glint_fit_opts ro = *base; /* the samples a fit takes */

	glint_fit_resolve_samples(&ro, scene->spp);
	for (int k = 0; k < GLINT_LADDER_NKNOBS; k++) {
		if (!knobs || knobs & 1u << k)
			continue;
		struct glint_ladder_knob *kn = &out->knob[k];
		int v = k == GLINT_LADDER_SPP	    ? scene->spp
			: k == GLINT_LADDER_SAMPLES ? ro.light_samples
			: k == GLINT_LADDER_DOF ? scene->cam.aperture_radius > 0
						: 1;
		kn->nlevels = 1;
		kn->level[0].value = v;
		*knob_value(&out->reference, k) = v;
		snprintf(kn->why, sizeof(kn->why),
			 "not tried: as the scene and options have it");
	}
}

/* Each knob's cheaper levels, one at a time from the reference fit: the
 * cheapest whose effect stays below the threshold is chosen. */
static void try_levels(struct ladder *l, struct glint_ladder_result *out,
		       double threshold)
{
	int which;

	for (int k = 0; k < GLINT_LADDER_NKNOBS; k++) {
		struct glint_ladder_knob *kn = &out->knob[k];
		kn->level[0].seconds = out->ref_seconds;
		kn->level[0].tried = 1;
		for (int i = 1; i < kn->nlevels; i++) {
			struct glint_ladder_setting s = out->reference;
			struct glint_fit_result fr;
			struct glint_ladder_level *lv = &kn->level[i];
			*knob_value(&s, k) = lv->value;
			if (fit_at(l, &s, out->ref_fit.p, &fr, &lv->seconds) <
			    0) {
				glint_log_warn("fidelity ladder: %s = %d: %s",
					       kn->name, lv->value,
					       glint_error_msg());
				lv->effect = INFINITY;
				continue;
			}
			lv->tried = 1;
			lv->effect = effect_of(&fr, &out->ref_fit, &which);
			lv->param = which;
			glint_log_info("fidelity ladder: %s %d: %.2f standard "
				       "errors, %.2f s",
				       kn->name, lv->value, lv->effect,
				       lv->seconds);
			if (lv->effect < threshold)
				kn->chosen = i;
		}
	}
}

/* The choices together: fitted, and while they move the fit by a
 * standard error or more, the knob whose own choice moved it most steps
 * back up. */
static int combine(struct ladder *l, struct glint_ladder_result *out,
		   const double *start, const struct glint_model *model)
{
	int which;

	for (;;) {
		for (int k = 0; k < GLINT_LADDER_NKNOBS; k++)
			*knob_value(&out->chosen, k) =
				out->knob[k].level[out->knob[k].chosen].value;
		int ret = fit_at(l, &out->chosen, start, &out->chosen_fit,
				 &out->chosen_seconds);
		if (ret < 0)
			return ret;
		out->final_effect =
			effect_of(&out->chosen_fit, &out->ref_fit, &which);
		out->final_param = which;
		if (out->final_effect < 1)
			return 0;
		int worst = -1;
		for (int k = 0; k < GLINT_LADDER_NKNOBS; k++) {
			struct glint_ladder_knob *kn = &out->knob[k];
			if (kn->chosen > 0 &&
			    (worst < 0 ||
			     kn->level[kn->chosen].effect >
				     out->knob[worst]
					     .level[out->knob[worst].chosen]
					     .effect))
				worst = k;
		}
		if (worst < 0)
			return 0; /* at the reference: the start matters */
		out->knob[worst].chosen--;
		out->backoffs++;
		glint_log_info("fidelity ladder: the choices together move %s "
			       "by %.2f standard errors; %s steps back up",
			       which >= 0 ? model->params[which].name : "?",
			       out->final_effect, out->knob[worst].name);
	}
}

int glint_ladder_run(const struct glint_scene *scene,
		     const struct glint_model *model,
		     const struct glint_image *photo,
		     const struct glint_image *weight,
		     const struct glint_fit_opts *base, double threshold,
		     unsigned knobs, int nthreads,
		     struct glint_ladder_result *out)
{
	struct ladder l = { 0 };
	int ret;

	memset(out, 0, sizeof(*out));
	if (glint_model_is_transparent(model))
		return glint_error_set(EINVAL,
				       "the fidelity ladder is for opaque "
				       "models; %s is fitted by following "
				       "its paths",
				       model->name);
	l.scene = *scene;
	l.model = model;
	l.photo = photo;
	l.weight = weight;
	l.base = *base;
	l.nthreads = nthreads;
	out->threshold = threshold;
	ret = glint_image_read(scene->env_path, &l.env_img);
	if (ret < 0)
		return glint_error_prefix(ret, "fidelity ladder");
	set_levels(&l, out);
	untried(out, scene, base, knobs);
	glint_log_info("fidelity ladder: reference fit (every knob tried at "
		       "its richest)");
	ret = fit_at(&l, &out->reference, base->start, &out->ref_fit,
		     &out->ref_seconds);
	if (ret < 0)
		goto done;
	try_levels(&l, out, threshold);
	ret = combine(&l, out, base->start, model);
	if (ret < 0)
		goto done;
	for (int k = 0; k < GLINT_LADDER_NKNOBS; k++)
		explain(&out->knob[k], model, threshold);
done:
	glint_image_free(l.env_img);
	for (int i = 0; i < 3; i++) {
		glint_image_free(l.photos[i]);
		glint_image_free(l.weights[i]);
	}
	return ret;
}

static json_t *setting_json(const struct glint_ladder_setting *s)
{
	return json_pack("{s:b, s:i, s:i, s:i, s:i}", "depth_of_field", s->dof,
			 "spp", s->spp, "image_downsample", s->res_factor,
			 "env_downsample", s->env_factor, "shading_samples",
			 s->samples);
}

json_t *glint_ladder_to_json(const struct glint_ladder_result *r)
{
	json_t *knobs = json_array();
	for (int k = 0; k < GLINT_LADDER_NKNOBS; k++) {
		const struct glint_ladder_knob *kn = &r->knob[k];
		json_t *lv = json_array();
		for (int i = 0; i < kn->nlevels; i++) {
			const struct glint_ladder_level *l = &kn->level[i];
			json_array_append_new(
				lv, json_pack("{s:i, s:o, s:f}", "value",
					      l->value, "effect_se",
					      isfinite(l->effect)
						      ? json_real(l->effect)
						      : json_null(),
					      "seconds", l->seconds));
		}
		json_array_append_new(knobs,
				      json_pack("{s:s, s:i, s:s, s:o}", "name",
						kn->name, "chosen",
						kn->level[kn->chosen].value,
						"why", kn->why, "levels", lv));
	}
	const char *fp = r->final_param >= 0
				 ? r->ref_fit.model->params[r->final_param].name
				 : "";
	return json_pack(
		"{s:f, s:o, s:o, s:o, s:{s:f, s:s, s:i}, s:f, s:f, s:[{s:s, "
		"s:i, s:s}, {s:s, s:s, s:s}]}",
		"threshold_se", r->threshold, "reference",
		setting_json(&r->reference), "chosen", setting_json(&r->chosen),
		"knobs", knobs, "final", "effect_se", r->final_effect,
		"parameter", fp, "backoffs", r->backoffs, "reference_seconds",
		r->ref_seconds, "chosen_seconds", r->chosen_seconds, "decided",
		"name", "bounce depth", "value", 1, "why",
		"a lone convex opaque sphere sees only the map: one bounce is "
		"exact",
		"name", "stand", "value", "not modelled", "why",
		"the scene has no geometry for the sample's support; mask "
		"the pixels it shadows with the weight image");
}

void glint_ladder_print(const struct glint_ladder_result *r, FILE *f)
{
	fprintf(f,
		"fidelity ladder (limit %.2f standard errors per knob; "
		"reference fit %.2f s):\n",
		r->threshold, r->ref_seconds);
	for (int k = 0; k < GLINT_LADDER_NKNOBS; k++) {
		const struct glint_ladder_knob *kn = &r->knob[k];
		fprintf(f, "  %-19s %3d  (", kn->name,
			kn->level[kn->chosen].value);
		for (int i = 0; i < kn->nlevels; i++)
			fprintf(f, "%s%d: %.2f se", i ? ", " : "",
				kn->level[i].value,
				i ? kn->level[i].effect : 0.0);
		fprintf(f, ")  %s\n", kn->why);
	}
	fprintf(f,
		"  chosen together: %.2f s, moves the fit by %.2f standard "
		"errors (%s)%s\n",
		r->chosen_seconds, r->final_effect,
		r->final_param >= 0
			? r->ref_fit.model->params[r->final_param].name
			: "-",
		r->backoffs ? ", after stepping back" : "");
}

int glint_ladder_knobs_parse(const char *list, unsigned *knobs)
{
	static const char *const short_names[GLINT_LADDER_NKNOBS] = {
		"dof", "spp", "resolution", "env", "samples"
	};
	char buf[256];
	*knobs = 0;
	snprintf(buf, sizeof(buf), "%s", list);
	for (char *save = NULL, *t = strtok_r(buf, ",", &save); t;
	     t = strtok_r(NULL, ",", &save)) {
		int k = 0;
		while (k < GLINT_LADDER_NKNOBS && strcmp(t, short_names[k]))
			k++;
		if (k == GLINT_LADDER_NKNOBS)
			return glint_error_set(
				EINVAL,
				"'%s': expected knobs among dof, "
				"spp, resolution, env, samples "
				"(comma-separated)",
				t);
		*knobs |= 1u << k;
	}
	if (!*knobs)
		return glint_error_set(EINVAL, "'%s': no knob named", list);
	return 0;
}
