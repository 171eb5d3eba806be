/* SPDX-License-Identifier: MIT */
/* Each light's photo fitted alone beside the joint fit, and each
 * parameter's drift with the light's angle (fit/per_light.h). */
#include "fit/per_light.h"

#include "fit/job.h"
#include "fit/misfit.h"

#include "core/error.h"
#include "core/json.h"
#include "core/log.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The angle between the brightest light of r's map and the direction
 * from the sphere to the camera, degrees. */
static double light_angle(const struct glint_renderer *r)
{
	struct vec3 l = glint_misfit_light(r->env);
	struct vec3 v =
		v3_norm(v3_sub(r->scene.cam.pos, r->scene.sphere_centre));
	return acos(fmax(-1, fmin(1, v3_dot(v3_norm(l), v)))) * 180 / M_PI;
}

/* Parameter k's weighted line against the angle, and chi^2 / dof about
 * the joint value. */
static void trend(struct glint_per_light *pl, int k, double joint)
{
	double sw = 0, sx = 0, sy = 0, sxx = 0, sxy = 0, chi2 = 0;
	double amin = INFINITY, amax = -INFINITY;
	int n = 0;
	for (int v = 0; v < pl->nviews; v++) {
		double se = pl->se[v][k];
		if (!isfinite(se) || !(se > 0))
			continue;
		double w = 1 / (se * se), x = pl->angle_deg[v] / 10,
		       y = pl->p[v][k];
		sw += w;
		sx += w * x;
		sy += w * y;
		sxx += w * x * x;
		sxy += w * x * y;
		chi2 += w * (y - joint) * (y - joint);
		amin = fmin(amin, pl->angle_deg[v]);
		amax = fmax(amax, pl->angle_deg[v]);
		n++;
	}
	pl->used[k] = n;
	pl->slope[k] = pl->slope_se[k] = pl->z[k] = NAN;
	pl->chi2_dof[k] = n > 0 ? chi2 / n : NAN;
	double det = sw * sxx - sx * sx;
	/* a slope needs two lights at least a degree apart */
	if (n < 2 || amax - amin < 1 || !(det > 0))
		return;
	pl->slope[k] = (sw * sxy - sx * sy) / det;
	pl->slope_se[k] = sqrt(sw / det);
	pl->z[k] = pl->slope[k] / pl->slope_se[k];
	pl->drifts[k] = fabs(pl->z[k]) >= GLINT_DRIFT_Z;
	pl->ndrift += pl->drifts[k];
}

static void verdict(struct glint_per_light *pl, const struct glint_model *m)
{
	size_t len = 0, n = sizeof(pl->verdict);
	int worst = -1;
	for (int k = 0; k < pl->nparams; k++)
		if (isfinite(pl->z[k]) &&
		    (worst < 0 || fabs(pl->z[k]) > fabs(pl->z[worst])))
			worst = k;
	if (worst < 0) {
		snprintf(pl->verdict, n,
			 "no trend to test: the lights are within a degree "
			 "of each other as seen from the view (not fitted "
			 "one by one)");
		return;
	}
	if (!pl->ndrift) {
		snprintf(pl->verdict, n,
			 "one material explains every light: no parameter "
			 "drifts with the light's angle from the view (the "
			 "largest, %s, by %.1f standard errors)",
			 m->params[worst].name, fabs(pl->z[worst]));
		return;
	}
	len = (size_t)snprintf(pl->verdict, n,
			       "one material does not explain every light: ");
	for (int k = 0, first = 1; k < pl->nparams && len < n; k++) {
		if (!pl->drifts[k])
			continue;
		len += (size_t)snprintf(pl->verdict + len, n - len,
					"%s%s drifts with the light's angle "
					"from the view (%+.3g per 10 deg, "
					"%.1f standard errors)",
					first ? "" : "; ", m->params[k].name,
					pl->slope[k], fabs(pl->z[k]));
		first = 0;
	}
	if (len < n)
		snprintf(pl->verdict + len, n - len,
			 ": the model or the lights are not what the photos "
			 "show");
}

int glint_fit_per_light(const struct glint_fit_view *views, int nv,
			const struct glint_model *model,
			const struct glint_fit_opts *o,
			const struct glint_fit_result *joint,
			struct glint_per_light *out)
{
	struct glint_fit_result *one = malloc(sizeof(*one));
	struct glint_fit_opts oo = *o;
	int ret = 0;

	memset(out, 0, sizeof(*out));
	if (!one)
		return glint_error_set(ENOMEM, "out of memory");
	out->nviews = nv;
	out->nparams = model->nparams;
	oo.progress = NULL;
	/* Lights at one angle from the view (one lamp, the turntable
	 * turned) have no trend to show: no fits. */
	double amin = INFINITY, amax = -INFINITY;
	for (int v = 0; v < nv; v++) {
		out->angle_deg[v] = light_angle(views[v].r);
		amin = fmin(amin, out->angle_deg[v]);
		amax = fmax(amax, out->angle_deg[v]);
	}
	int fit = amax - amin >= 1;
	for (int v = 0; !fit && v < nv; v++) {
		out->rel_rmse[v] = NAN;
		for (int k = 0; k < model->nparams; k++)
			out->p[v][k] = out->se[v][k] = NAN;
	}
	for (int v = 0; fit && v < nv && ret == 0; v++) {
		glint_log_info("per-light fits: photo %d of %d alone", v + 1,
			       nv);
		/* its own map's sources alone, as photo 1 of 1 */
		struct glint_fit_light_source own[GLINT_FIT_MAX_SOURCES];
		oo.sources = own;
		oo.nsources = 0;
		for (int s = 0; s < o->nsources; s++)
			if (o->sources[s].view == v) {
				own[oo.nsources] = o->sources[s];
				own[oo.nsources++].view = 0;
			}
		ret = glint_fit_views(&views[v], 1, model, &oo, one);
		if (ret < 0) {
			ret = glint_error_prefix(ret,
						 "per-light fit of photo "
						 "%d of %d",
						 v + 1, nv);
			break;
		}
		out->rel_rmse[v] = one->rel_rmse;
		for (int k = 0; k < model->nparams; k++) {
			out->p[v][k] = one->p[k];
			out->se[v][k] = glint_fit_undetermined(one, k)
						? INFINITY
						: one->se[k];
		}
	}
	free(one);
	if (ret < 0)
		return ret;
	for (int k = 0; k < model->nparams; k++)
		trend(out, k, joint->p[k]);
	verdict(out, model);
	return 0;
}

json_t *glint_per_light_json(const struct glint_per_light *pl,
			     const struct glint_model *model)
{
	json_t *lights = json_array(), *trends = json_array();
	for (int v = 0; v < pl->nviews; v++) {
		json_t *vals = json_object(), *ses = json_object();
		for (int k = 0; k < pl->nparams; k++) {
			json_object_set_new(
				vals, model->params[k].name,
				glint_json_real_or_null(pl->p[v][k]));
			json_object_set_new(
				ses, model->params[k].name,
				glint_json_real_or_null(pl->se[v][k]));
		}
		json_array_append_new(
			lights,
			json_pack("{s:i,s:f,s:o,s:o,s:o}", "photo", v + 1,
				  "light_angle_deg", pl->angle_deg[v],
				  "relative_rmse",
				  glint_json_real_or_null(pl->rel_rmse[v]),
				  "values", vals, "stderr", ses));
	}
	for (int k = 0; k < pl->nparams; k++)
		json_array_append_new(
			trends,
			json_pack("{s:s,s:i,s:o,s:o,s:o,s:o,s:b}", "parameter",
				  model->params[k].name, "lights", pl->used[k],
				  "slope_per_10deg",
				  glint_json_real_or_null(pl->slope[k]),
				  "slope_stderr",
				  glint_json_real_or_null(pl->slope_se[k]), "z",
				  glint_json_real_or_null(pl->z[k]),
				  "chi2_dof_about_joint",
				  glint_json_real_or_null(pl->chi2_dof[k]),
				  "drifts", pl->drifts[k]));
	return json_pack("{s:s,s:o,s:o,s:s,s:f}", "what",
			 "each photo fitted alone with the joint fit's model; "
			 "each parameter's weighted line against the angle "
			 "of the photo's brightest light from the view "
			 "(weights from each fit's whole standard error); a "
			 "drift at |z| >= 3",
			 "lights", lights, "trends", trends, "verdict",
			 pl->verdict, "drift_z", GLINT_DRIFT_Z);
}
