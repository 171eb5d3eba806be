/* SPDX-License-Identifier: MIT */
/* glTF 2.0: a UV sphere (its mesh embedded) carrying the metallic-roughness
 * material with KHR_materials_ior and
 * _specular; a transparent sphere with _transmission and _volume
 * (export/target.h). */
#define _GNU_SOURCE /* asprintf */
#include "export/target.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The sphere's diameter when the fit records none (metres). */
#define GLTF_DIAMETER_M 0.1

enum { G_BASE = 0, G_ROUGH = 3, G_SPEC = 4, G_SCOL = 5, G_NX = 8 };

/* glTF: separable Smith visibility of the specification. */
static double gltf_v(double nl, double nv, double a2)
{
	nl = fabs(nl);
	nv = fabs(nv);
	return 1 / ((nl + sqrt(a2 + (1 - a2) * nl * nl)) *
		    (nv + sqrt(a2 + (1 - a2) * nv * nv)));
}

static void gltf_brdf(const double *x, double ior, struct vec3 wo,
		      struct vec3 wi, struct vec3 h, double f[3])
{
	double a = x[G_ROUGH] * x[G_ROUGH], a2 = a * a;
	double t = h.z * h.z * (a2 - 1) + 1;
	double dv = a2 / (M_PI * t * t) * gltf_v(wi.z, wo.z, a2);
	double w5 = pow(1 - fabs(v3_dot(wo, h)), 5);
	double f0 = glint_export_schlick_f0(ior), s = x[G_SPEC];

	for (int c = 0; c < 3; c++) {
		double c0 = fmin(f0 * x[G_SCOL + c], 1) * s;
		double F = c0 + (s - c0) * w5;
		f[c] = (1 - F) * x[G_BASE + c] / M_PI + F * dv;
	}
}

static void gltf_eval(const double *x, const struct glint_export *e,
		      const void *view, struct vec3 wo, struct vec3 wi,
		      struct vec3 h, double f[3])
{
	(void)view;
	gltf_brdf(x, e->ior, wo, wi, h, f);
}

static int gltf_start(const struct glint_model *model, const double *p,
		      const struct glint_export *e, double *x, double *lo,
		      double *hi)
{
	double kd[3], ks[3], ksm, w;
	glint_export_lobes(model, p, kd, ks, &ksm, &w);
	for (int c = 0; c < 3; c++) {
		glint_export_set(x, lo, hi, G_BASE + c, kd[c], 0, 1);
		glint_export_set(
			x, lo, hi, G_SCOL + c, ksm > 0 ? ks[c] / ksm : 1, 0,
			1 / glint_export_schlick_f0(fmax(e->ior, 1.01)));
	}
	glint_export_set(x, lo, hi, G_ROUGH, sqrt(w), 0.02, 1);
	glint_export_set(x, lo, hi, G_SPEC, ksm, 0, 1);
	return G_NX;
}

/* The sphere the material is shown on: NSEG segments around, NRING rings
 * from pole to pole, y up (glTF's), counter-clockwise seen from outside. */
enum { NSEG = 64, NRING = 32, NVERT = (NSEG + 1) * (NRING + 1) };
enum { NTRI = NSEG * (2 * NRING - 2), NIDX = 3 * NTRI };
enum { POS_OFF = 0, NRM_OFF = 12 * NVERT, IDX_OFF = 24 * NVERT };
enum { NBYTES = IDX_OFF + 2 * NIDX };

static void put_u32(unsigned char *b, uint32_t v)
{
	for (int k = 0; k < 4; k++)
		b[k] = (unsigned char)(v >> 8 * k); /* glTF is little-endian */
}

static void put_f32(unsigned char *b, float f)
{
	uint32_t v;
	memcpy(&v, &f, 4);
	put_u32(b, v);
}

/* The sphere of radius r into b (NBYTES), its positions' bounds into
 * lo, hi. */
static void sphere_mesh(double r, unsigned char *b, float lo[3], float hi[3])
{
	for (int c = 0; c < 3; c++)
		lo[c] = INFINITY, hi[c] = -INFINITY;
	for (int i = 0; i <= NRING; i++) {
		double t = M_PI * i / NRING;
		for (int j = 0; j <= NSEG; j++) {
			double ph = 2 * M_PI * j / NSEG;
			/* The seam's and poles' copies bit-identical. */
			double n[3] = { i % NRING ? sin(t) * cos(ph) : 0,
					i == 0	     ? 1
					: i == NRING ? -1
						     : cos(t),
					i % NRING && j % NSEG
						? -sin(t) * sin(ph)
						: 0 };
			int v = i * (NSEG + 1) + j;
			for (int c = 0; c < 3; c++) {
				float pf = (float)(r * n[c]);
				put_f32(b + POS_OFF + 12 * v + 4 * c, pf);
				put_f32(b + NRM_OFF + 12 * v + 4 * c,
					(float)n[c]);
				lo[c] = fminf(lo[c], pf);
				hi[c] = fmaxf(hi[c], pf);
			}
		}
	}
	unsigned char *q = b + IDX_OFF;
	for (int i = 0; i < NRING; i++)
		for (int j = 0; j < NSEG; j++) {
			int a = i * (NSEG + 1) + j, d = a + NSEG + 1;
			int tri[2][3] = { { a, d, a + 1 },
					  { a + 1, d, d + 1 } };
			for (int k = 0; k < 2; k++) {
				/* The poles' triangles have one, not two. */
				if ((i == 0 && k == 0) ||
				    (i == NRING - 1 && k == 1))
					continue;
				for (int c = 0; c < 3; c++, q += 2) {
					q[0] = (unsigned char)(tri[k][c] &
							       0xff);
					q[1] = (unsigned char)(tri[k][c] >> 8);
				}
			}
		}
}

/* Standard base64 (RFC 4648) of n bytes, for a data URI: malloc'd. */
static char *base64(const unsigned char *b, size_t n)
{
	static const char a[] =
		"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz"
		"0123456789+/";
	char *s = malloc(4 * ((n + 2) / 3) + 1), *o = s;
	if (!s)
		return NULL;
	for (size_t k = 0; k < n; k += 3) {
		uint32_t v = (uint32_t)b[k] << 16;
		if (k + 1 < n)
			v |= (uint32_t)b[k + 1] << 8;
		if (k + 2 < n)
			v |= b[k + 2];
		*o++ = a[v >> 18];
		*o++ = a[(v >> 12) & 63];
		*o++ = k + 1 < n ? a[(v >> 6) & 63] : '=';
		*o++ = k + 2 < n ? a[v & 63] : '=';
	}
	*o = 0;
	return s;
}

/* The document around material mat: a node with the sphere of diameter d
 * metres (its mesh embedded as a data URI), named name; NULL when out of
 * memory.  Takes mat and extensions. */
static json_t *gltf_wrap(const char *name, json_t *mat, json_t *extensions,
			 double d)
{
	unsigned char *b = malloc(NBYTES);
	float lo[3], hi[3];
	char *b64 = NULL, *uri = NULL;
	json_t *doc = NULL;

	if (b) {
		sphere_mesh(d / 2, b, lo, hi);
		b64 = base64(b, NBYTES);
	}
	if (b64 &&
	    asprintf(&uri, "data:application/octet-stream;base64,%s", b64) < 0)
		uri = NULL;
	if (uri)
		doc = json_pack(
			"{s:{s:s, s:s}, s:o, s:i, s:[{s:[i]}], "
			"s:[{s:s, s:i}], "
			"s:[{s:s, s:[{s:{s:i, s:i}, s:i, s:i, s:i}]}], "
			"s:o, s:[{s:i, s:s}], "
			"s:[{s:i, s:i, s:i, s:i}, {s:i, s:i, s:i, s:i}, "
			"{s:i, s:i, s:i, s:i}], "
			"s:[{s:i, s:i, s:i, s:s, s:[f,f,f], s:[f,f,f]}, "
			"{s:i, s:i, s:i, s:s}, {s:i, s:i, s:i, s:s}]}",
			"asset", "version", "2.0", "generator", "glint export",
			"extensionsUsed", extensions, "scene", 0, "scenes",
			"nodes", 0, "nodes", "name", name, "mesh", 0, "meshes",
			"name", name, "primitives", "attributes", "POSITION", 0,
			"NORMAL", 1, "indices", 2, "material", 0, "mode", 4,
			"materials", json_pack("[o]", mat), "buffers",
			"byteLength", NBYTES, "uri", uri, "bufferViews",
			"buffer", 0, "byteOffset", POS_OFF, "byteLength",
			12 * NVERT, "target", 34962, "buffer", 0, "byteOffset",
			NRM_OFF, "byteLength", 12 * NVERT, "target", 34962,
			"buffer", 0, "byteOffset", IDX_OFF, "byteLength",
			2 * NIDX, "target", 34963, "accessors", "bufferView", 0,
			"componentType", 5126, "count", NVERT, "type", "VEC3",
			"min", (double)lo[0], (double)lo[1], (double)lo[2],
			"max", (double)hi[0], (double)hi[1], (double)hi[2],
			"bufferView", 1, "componentType", 5126, "count", NVERT,
			"type", "VEC3", "bufferView", 2, "componentType", 5123,
			"count", NIDX, "type", "SCALAR");
	else {
		json_decref(mat);
		json_decref(extensions);
	}
	free(uri);
	free(b64);
	free(b);
	return doc;
}

/* glTF: KHR_materials_transmission and _volume (attenuation colour T at
 * distance d: exactly T per diameter). */
static json_t *gltf_dielectric(const struct glint_export *e, const char *name,
			       json_t *glint)
{
	const double *x = e->x, d = e->diameter_m;
	json_t *mat = json_pack(
		"{s:s, s:{s:[f,f,f,f], s:f, s:f}, s:{s:{s:f}, s:{s:f}, "
		"s:{s:f, s:f, s:[f,f,f]}}, s:{s:o}}",
		"name", name, "pbrMetallicRoughness", "baseColorFactor", 1.0,
		1.0, 1.0, 1.0, "metallicFactor", 0.0, "roughnessFactor", 0.0,
		"extensions", "KHR_materials_ior", "ior", e->ior,
		"KHR_materials_transmission", "transmissionFactor", 1.0,
		"KHR_materials_volume", "thicknessFactor", d,
		"attenuationDistance", d, "attenuationColor", x[0], x[1], x[2],
		"extras", "glint", glint);
	return gltf_wrap(name, mat,
			 json_pack("[s, s, s]", "KHR_materials_ior",
				   "KHR_materials_transmission",
				   "KHR_materials_volume"),
			 d);
}

static json_t *gltf_document(const struct glint_export *e, const char *name,
			     const char *source,
			     const struct glint_model *model)
{
	const double *x = e->x;
	json_t *glint = json_pack("{s:s, s:s, s:f, s:s}", "source", source,
				  "model", model->name, "refit_relative_rms",
				  e->residual, "note", glint_export_note_of(e));
	if (e->dielectric)
		return gltf_dielectric(e, name, glint);
	json_t *mat = json_pack(
		"{s:s, s:{s:[f,f,f,f], s:f, s:f}, s:{s:{s:f}, s:{s:f, "
		"s:[f,f,f]}}, s:{s:o}}",
		"name", name, "pbrMetallicRoughness", "baseColorFactor",
		x[G_BASE], x[G_BASE + 1], x[G_BASE + 2], 1.0, "metallicFactor",
		0.0, "roughnessFactor", x[G_ROUGH], "extensions",
		"KHR_materials_ior", "ior", e->ior, "KHR_materials_specular",
		"specularFactor", x[G_SPEC], "specularColorFactor", x[G_SCOL],
		x[G_SCOL + 1], x[G_SCOL + 2], "extras", "glint", glint);
	return gltf_wrap(name, mat,
			 json_pack("[s, s]", "KHR_materials_ior",
				   "KHR_materials_specular"),
			 e->diameter_m > 0 ? e->diameter_m : GLTF_DIAMETER_M);
}

static char *gltf_text(const struct glint_export *e, const char *name,
		       const char *source, const struct glint_model *model)
{
	json_t *doc = gltf_document(e, name, source, model);
	char *text = doc ? json_dumps(doc, JSON_INDENT(2)) : NULL;
	json_decref(doc);
	return text;
}

static json_t *gltf_params(const struct glint_export *e)
{
	const double *x = e->x;
	return json_pack("{s:[f,f,f], s:f, s:f, s:f, s:[f,f,f]}", "base_color",
			 x[G_BASE], x[G_BASE + 1], x[G_BASE + 2], "roughness",
			 x[G_ROUGH], "ior", e->ior, "specular", x[G_SPEC],
			 "specular_color", x[G_SCOL], x[G_SCOL + 1],
			 x[G_SCOL + 2]);
}

const struct glint_export_target glint_export_target_gltf = {
	.name = "gltf",
	.extension = ".gltf",
	.brdf = gltf_eval,
	.view = NULL,
	.start = gltf_start,
	.text = gltf_text,
	.params = gltf_params,
	.schlick = 1,
};
