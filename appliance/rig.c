/* SPDX-License-Identifier: MIT */
/*
 * The rig file (docs/rig.md): camera, bracket, ROIs, optics, sample, the
 * board's lines by role and the capture sequence.  Validated on load;
 * every message names the file, the key and what was expected.
 */
#define _POSIX_C_SOURCE 200809L
#include "appliance/rig.h"

#include "core/error.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const char *const glint_rig_step_names[GLINT_RIG_STEP_COUNT] = {
	"lights on",
	"lights off",
	"turntable probe",
	"turntable sample",
	"capture probe",
	"capture sample",
	"fit",
	"light 1",
	"light 2",
	"light 3",
	"light 4",
	"turntable reference",
	"capture reference",
};

static int load_line(const char *path, const char *where, json_t *o,
		     struct glint_line_cfg *l)
{
	static const char *const keys[] = { "chip", "line", "active_low",
					    NULL };
	const char *chip = NULL;
	json_t *line;
	int ret = glint_json_known_keys(path, where, o, keys);

	if (!ret)
		ret = glint_json_string(path, where, o, "chip", 1, &chip);
	if (ret)
		return ret;
	snprintf(l->chip, sizeof(l->chip), "%s", chip);
	line = json_object_get(o, "line");
	if (json_is_integer(line) && json_integer_value(line) >= 0 &&
	    json_integer_value(line) < 4096) {
		l->offset = (int)json_integer_value(line);
	} else if (json_is_string(line) && json_string_length(line) > 0 &&
		   json_string_length(line) < sizeof(l->name)) {
		snprintf(l->name, sizeof(l->name), "%s",
			 json_string_value(line));
	} else {
		return glint_error_set(EINVAL,
				       "%s: %s.line: expected a line offset "
				       "(0..4095) or a line name",
				       path, where);
	}
	l->active_low = 0;
	ret = glint_json_bool(path, where, o, "active_low", &l->active_low);
	l->used = ret == 0;
	return ret;
}

/* board.lines.lights as a list: one line per lamp, lamp 1 first. */
static int load_light_list(const char *path, json_t *v,
			   struct glint_board_cfg *c)
{
	size_t n = json_array_size(v);
	if (n < 1 || n > GLINT_MAX_LIGHTS)
		return glint_error_set(EINVAL,
				       "%s: board.lines.lights: expected a "
				       "line or a list of 1..%d lines (one "
				       "per lamp)",
				       path, GLINT_MAX_LIGHTS);
	for (size_t k = 0; k < n; k++) {
		char where[64];
		snprintf(where, sizeof(where), "board.lines.lights[%zu]", k);
		int ret = load_line(path, where, json_array_get(v, k),
				    &c->lines[glint_role_light((int)k + 1)]);
		if (ret)
			return ret;
	}
	return 0;
}

/* board.lines: each key a role, each value a chip and line. */
static int load_lines(const char *path, json_t *lines,
		      struct glint_board_cfg *c)
{
	const char *key;
	json_t *v;

	json_object_foreach(lines, key, v)
	{
		int role = 0;
		/* lights[2].. come only from the lights list */
		while (role < GLINT_ROLE_LIGHTS_2 &&
		       strcmp(key, glint_role_name(role)))
			role++;
		if (role == GLINT_ROLE_LIGHTS && json_is_array(v)) {
			int ret = load_light_list(path, v, c);
			if (ret)
				return ret;
			continue;
		}
		if (role == GLINT_ROLE_LIGHTS_2)
			return glint_error_set(EINVAL,
					       "%s: board.lines.%s: unknown "
					       "role; expected button, lights "
					       "(a line or a list), led, "
					       "turntable_step, "
					       "turntable_dir, "
					       "turntable_enable or position",
					       path, key);
		char where[64];
		snprintf(where, sizeof(where), "board.lines.%s", key);
		int ret = load_line(path, where, v, &c->lines[role]);
		if (ret)
			return ret;
	}
	return 0;
}

/* board.turntable: how it turns and where the probe and sample face. */
static int load_turntable(const char *path, json_t *tt,
			  struct glint_board_cfg *c)
{
	static const char *const keys[] = {
		"mode",		 "steps_per_turn", "step_hz",
		"relay_pulse_s", "probe_deg",	   "sample_deg",
		"reference_deg", "settle_s",	   NULL
	};
	static const char *const modes[] = { "stepper", "relay", "none", NULL };
	static const enum glint_turntable_mode mode_of[] = { GLINT_TT_STEPPER,
							     GLINT_TT_RELAY,
							     GLINT_TT_NONE };
	const char *w = "board.turntable", *mode = NULL;
	double steps = c->steps_per_turn;
	int ret = glint_json_known_keys(path, w, tt, keys);

	if (!ret)
		ret = glint_json_string(path, w, tt, "mode", 1, &mode);
	if (!ret) {
		int i = 0;
		while (modes[i] && strcmp(mode, modes[i]))
			i++;
		if (modes[i])
			c->tt_mode = mode_of[i];
		else
			ret = glint_error_set(EINVAL,
					      "%s: board.turntable.mode = "
					      "\"%s\": expected stepper, relay "
					      "or none",
					      path, mode);
	}
	if (!ret)
		ret = glint_json_number(path, w, tt, "steps_per_turn", 0,
					(struct glint_range){ 1, 1e6, 0, 0 },
					&steps);
	c->steps_per_turn = (int)steps;
	if (!ret)
		ret = glint_json_number(path, w, tt, "step_hz", 0,
					(struct glint_range){ 0, 1e5, 1, 0 },
					&c->step_hz);
	if (!ret)
		ret = glint_json_number(path, w, tt, "relay_pulse_s", 0,
					(struct glint_range){ 0, 10, 1, 0 },
					&c->relay_pulse_s);
	if (!ret)
		ret = glint_json_number(path, w, tt, "probe_deg", 0,
					(struct glint_range){ -360, 360, 0, 0 },
					&c->probe_deg);
	if (!ret)
		ret = glint_json_number(path, w, tt, "sample_deg", 0,
					(struct glint_range){ -360, 360, 0, 0 },
					&c->sample_deg);
	if (!ret)
		ret = glint_json_number(path, w, tt, "reference_deg", 0,
					(struct glint_range){ -360, 360, 0, 0 },
					&c->reference_deg);
	if (!ret)
		ret = glint_json_number(path, w, tt, "settle_s", 0,
					(struct glint_range){ 0, 60, 0, 0 },
					&c->settle_s);
	return ret;
}

/* The keys board may hold: the common ones and those its backend
 * reads. */
static int check_board_keys(const char *path, json_t *b, const char *backend)
{
	static const char *const common[] = { "backend", "lines", "debounce_ms",
					      "turntable" };
	const struct glint_board_ops *ops = glint_board_backend(backend);
	const char *keys[16];
	int n = 0;

	for (size_t i = 0; i < sizeof(common) / sizeof(*common); i++)
		keys[n++] = common[i];
	for (int i = 0; ops && ops->cfg_keys && ops->cfg_keys[i] && n < 15; i++)
		keys[n++] = ops->cfg_keys[i];
	keys[n] = NULL;
	return glint_json_known_keys(path, "board", b, keys);
}

static int load_board(const char *path, struct glint_rig *r)
{
	struct glint_board_cfg *c = &r->board;
	json_t *b = NULL, *lines = NULL, *tt = NULL;
	const char *backend = NULL;
	double ms = 30;
	int ret;

	glint_board_default_cfg(c);
	ret = glint_json_object(path, "", r->doc, "board", 0, &b);
	if (ret || !b)
		return ret;
	r->has_board = 1;
	c->backend_opts = b;
	c->rig_file = r->path;
	ret = glint_json_string(path, "board", b, "backend", 1, &backend);
	if (!ret) {
		snprintf(c->backend, sizeof(c->backend), "%s", backend);
		ret = check_board_keys(path, b, backend);
	}
	if (!ret)
		ret = glint_json_number(path, "board", b, "debounce_ms", 0,
					(struct glint_range){ 0, 1000, 0, 0 },
					&ms);
	c->debounce_s = ms / 1000;
	if (!ret)
		ret = glint_json_object(path, "board", b, "lines", 1, &lines);
	if (!ret)
		ret = load_lines(path, lines, c);
	if (!ret)
		ret = glint_json_object(path, "board", b, "turntable", 0, &tt);
	if (!ret && tt)
		ret = load_turntable(path, tt, c);
	if (!ret)
		ret = glint_board_cfg_check(path, c);
	return ret;
}

/* The default: one lamp (or all on one line), or each lamp in turn. */
static void default_sequence(struct glint_rig *r)
{
	static const enum glint_rig_step one[] = {
		GLINT_RIG_TURNTABLE_PROBE,
		GLINT_RIG_CAPTURE_PROBE,
		GLINT_RIG_TURNTABLE_SAMPLE,
		GLINT_RIG_CAPTURE_SAMPLE,
	};
	int nl = r->has_board ? glint_board_cfg_nlights(&r->board) : 0;

	r->nsteps = 0;
	for (int k = 1; k <= (nl > 1 ? nl : 1); k++) {
		r->steps[r->nsteps++] = nl > 1 ? GLINT_RIG_LIGHT_1 + k - 1
					       : GLINT_RIG_LIGHTS_ON;
		for (size_t i = 0; i < sizeof(one) / sizeof(*one); i++) {
			r->steps[r->nsteps++] = one[i];
			/* the gray ball at its own position, after the
			 * probe it calibrates */
			if (one[i] == GLINT_RIG_CAPTURE_PROBE &&
			    r->capture.ref_own) {
				r->steps[r->nsteps++] =
					GLINT_RIG_TURNTABLE_REFERENCE;
				r->steps[r->nsteps++] =
					GLINT_RIG_CAPTURE_REFERENCE;
			}
		}
	}
	r->steps[r->nsteps++] = GLINT_RIG_LIGHTS_OFF;
	r->steps[r->nsteps++] = GLINT_RIG_FIT;
}

static int load_sequence(const char *path, struct glint_rig *r)
{
	json_t *seq = json_object_get(r->doc, "sequence");
	int nl = r->has_board ? glint_board_cfg_nlights(&r->board) : 0,
	    samples = 0;

	if (!seq) {
		default_sequence(r);
		return 0;
	}
	if (!json_is_array(seq) || json_array_size(seq) == 0 ||
	    json_array_size(seq) > GLINT_RIG_MAX_STEPS)
		return glint_error_set(EINVAL,
				       "%s: sequence: expected a list of 1..%d "
				       "steps",
				       path, GLINT_RIG_MAX_STEPS);
	for (size_t i = 0; i < json_array_size(seq); i++) {
		const char *s = json_string_value(json_array_get(seq, i));
		int k = 0;
		while (s && k < GLINT_RIG_STEP_COUNT &&
		       strcmp(s, glint_rig_step_names[k]))
			k++;
		if (!s || k == GLINT_RIG_STEP_COUNT)
			return glint_error_set(
				EINVAL,
				"%s: sequence[%zu] = %s: expected one of "
				"\"lights on\", \"lights off\", \"light "
				"K\" (1..%d), \"turntable probe\", "
				"\"turntable sample\", \"turntable "
				"reference\", \"capture probe\", \"capture "
				"reference\", \"capture sample\", \"fit\"",
				path, i, s ? s : "(not a string)",
				GLINT_MAX_LIGHTS);
		if (k >= GLINT_RIG_LIGHT_1 && k <= GLINT_RIG_LIGHT_4 &&
		    k - GLINT_RIG_LIGHT_1 >= nl)
			return glint_error_set(
				EINVAL,
				"%s: sequence[%zu] = %s: the board has %d "
				"light line%s (board.lines.lights: a list, "
				"one line per lamp)",
				path, i, s, nl, nl == 1 ? "" : "s");
		if (k == GLINT_RIG_CAPTURE_SAMPLE &&
		    ++samples > GLINT_RIG_MAX_SAMPLES)
			return glint_error_set(EINVAL,
					       "%s: sequence[%zu]: more than "
					       "%d sample captures in a run",
					       path, i, GLINT_RIG_MAX_SAMPLES);
		r->steps[r->nsteps++] = k;
	}
	return 0;
}

/* bracket: how the exposure bracket is planned. */
static int load_bracket(const char *path, json_t *br,
			struct glint_bracket_opts *o)
{
	static const char *const keys[] = { "step_ev",	  "max_frames",
					    "max_time_s", "floor_dn",
					    "start_s",	  "max_drop",
					    NULL };
	int ret = glint_json_known_keys(path, "bracket", br, keys);

	if (!ret)
		ret = glint_json_number(path, "bracket", br, "step_ev", 0,
					(struct glint_range){ 0.25, 4, 0, 0 },
					&o->step_ev);
	if (!ret)
		ret = glint_json_int(path, "bracket", br, "max_frames", 0, 1,
				     GLINT_BRACKET_MAX, &o->max_frames);
	if (!ret)
		ret = glint_json_number(path, "bracket", br, "max_time_s", 0,
					(struct glint_range){ 0, 3600, 0, 1 },
					&o->max_time_s);
	if (!ret)
		ret = glint_json_number(path, "bracket", br, "floor_dn", 0,
					(struct glint_range){ 0, 1e4, 0, 0 },
					&o->floor_dn);
	if (!ret)
		ret = glint_json_number(path, "bracket", br, "start_s", 0,
					(struct glint_range){ 0, 60, 0, 0 },
					&o->start_s);
	if (!ret)
		ret = glint_json_int(path, "bracket", br, "max_drop", 0, 0, 64,
				     &o->max_drop);
	return ret;
}

/* sample (the sphere's size) and optics (the camera's intrinsics). */
static int load_optics(const char *path, json_t *doc,
		       struct glint_capture_setup *c)
{
	static const char *const opt_keys[] = {
		"focal_px",	"principal", "pixel_pitch_um",
		"psf_sigma_px", "olpf",	     NULL
	};
	static const char *const sample_keys[] = { "diameter_m", NULL };
	json_t *opt = NULL, *smp = NULL;
	int ret;

	c->principal[0] = c->principal[1] = -1;
	c->pitch_um = 1;
	c->diameter_m = 0.1;
	ret = glint_json_object(path, "", doc, "sample", 0, &smp);
	if (!ret && smp)
		ret = glint_json_known_keys(path, "sample", smp, sample_keys);
	if (!ret && smp)
		ret = glint_json_number(path, "sample", smp, "diameter_m", 0,
					(struct glint_range){ 0, 10, 1, 0 },
					&c->diameter_m);
	if (!ret)
		ret = glint_json_object(path, "", doc, "optics", 0, &opt);
	if (ret || !opt)
		return ret;
	ret = glint_json_known_keys(path, "optics", opt, opt_keys);
	if (!ret)
		ret = glint_json_number(path, "optics", opt, "focal_px", 1,
					(struct glint_range){ 1, 1e6, 0, 0 },
					&c->focal_px);
	if (!ret)
		ret = glint_json_numbers(path, "optics", opt, "principal", 0, 2,
					 (struct glint_range){ 0, 1e5, 0, 0 },
					 c->principal);
	if (!ret)
		ret = glint_json_number(
			path, "optics", opt, "pixel_pitch_um", 0,
			(struct glint_range){ 0, 1000, 1, 0 }, &c->pitch_um);
	if (!ret)
		ret = glint_json_number(path, "optics", opt, "psf_sigma_px", 0,
					(struct glint_range){ 0, 8, 0, 0 },
					&c->psf_sigma_px);
	if (!ret)
		ret = glint_json_bool(path, "optics", opt, "olpf", &c->olpf);
	return ret;
}

/* roi: where the probe and the sample are looked for in the frame. */
static int load_roi(const char *path, json_t *doc,
		    struct glint_capture_setup *c)
{
	static const char *const keys[] = { "probe", "sample", NULL };
	json_t *roi = NULL;
	int ret = glint_json_object(path, "", doc, "roi", 0, &roi);

	if (!ret && roi)
		ret = glint_json_known_keys(path, "roi", roi, keys);
	for (int k = 0; k < 2 && !ret && roi; k++) {
		double v[4] = { 0, 0, 0, 0 };
		ret = glint_json_numbers(
			path, "roi", roi, k ? "sample" : "probe", 0, 4,
			(struct glint_range){ 0, 65536, 0, 0 }, v);
		c->roi[k] = (struct glint_roi){ (int)v[0], (int)v[1], (int)v[2],
						(int)v[3] };
	}
	return ret;
}

/* reference: the gray ball (its albedo, the albedo's uncertainty, where
 * it is in its photo: the probe's beside the chrome ball, or its own at
 * the turntable's reference position, where roi may be left out). */
static int load_reference(const char *path, json_t *doc,
			  struct glint_capture_setup *c)
{
	static const char *const keys[] = { "albedo", "albedo_sigma", "roi",
					    NULL };
	json_t *ref = NULL;
	double v[4] = { 0, 0, 0, 0 };
	int ret = glint_json_object(path, "", doc, "reference", 0, &ref);

	if (ret || !ref)
		return ret;
	ret = glint_json_known_keys(path, "reference", ref, keys);
	if (!ret)
		ret = glint_json_number(path, "reference", ref, "albedo", 1,
					(struct glint_range){ 0, 1, 1, 0 },
					&c->ref_albedo);
	if (!ret)
		ret = glint_json_number(path, "reference", ref, "albedo_sigma",
					0, (struct glint_range){ 0, 1, 0, 0 },
					&c->ref_albedo_sigma);
	if (!ret)
		ret = glint_json_numbers(path, "reference", ref, "roi", 0, 4,
					 (struct glint_range){ 0, 65536, 0, 0 },
					 v);
	if (!ret && json_object_get(ref, "roi") &&
	    !(v[2] > v[0] && v[3] > v[1]))
		ret = glint_error_set(EINVAL,
				      "%s: reference.roi: expected [x0, y0, "
				      "x1, y1] with x1 > x0 and y1 > y0",
				      path);
	c->ref_roi = (struct glint_roi){ (int)v[0], (int)v[1], (int)v[2],
					 (int)v[3] };
	/* no roi: not in the probe's photo, so in a photo of its own */
	c->ref_own = !json_object_get(ref, "roi");
	return ret;
}

/* The gray ball's photo: its own ("capture reference", after a "capture
 * probe", on a table with a third position) or the probe's (its roi
 * there). */
static int check_reference(const char *path, struct glint_rig *r)
{
	struct glint_capture_setup *c = &r->capture;
	int probe = 0, own = 0;
	for (int i = 0; i < r->nsteps; i++) {
		enum glint_rig_step s = r->steps[i];
		probe |= s == GLINT_RIG_CAPTURE_PROBE;
		if (s != GLINT_RIG_CAPTURE_REFERENCE &&
		    s != GLINT_RIG_TURNTABLE_REFERENCE)
			continue;
		if (!(c->ref_albedo > 0))
			return glint_error_set(EINVAL,
					       "%s: sequence[%d] = %s: the rig "
					       "has no \"reference\" section "
					       "(the gray ball's albedo)",
					       path, i,
					       glint_rig_step_names[s]);
		if (r->has_board && r->board.tt_mode == GLINT_TT_RELAY)
			return glint_error_set(
				EINVAL,
				"%s: sequence[%d] = %s: a relay turntable has "
				"two positions, probe and sample (a stepper "
				"has board.turntable.reference_deg; or put the "
				"gray ball beside the probe, reference.roi)",
				path, i, glint_rig_step_names[s]);
		if (s == GLINT_RIG_CAPTURE_REFERENCE && !probe)
			return glint_error_set(EINVAL,
					       "%s: sequence[%d] = capture "
					       "reference before any \"capture "
					       "probe\": it calibrates the "
					       "probe's map",
					       path, i);
		if (s == GLINT_RIG_CAPTURE_REFERENCE)
			own = 1;
	}
	if (c->ref_albedo > 0 && c->ref_own && !own &&
	    json_object_get(r->doc, "sequence"))
		return glint_error_set(EINVAL,
				       "%s: reference without a roi (the gray "
				       "ball in a photo of its own) but no "
				       "\"capture reference\" step in the "
				       "sequence: add \"turntable "
				       "reference\", \"capture reference\" "
				       "after \"capture probe\", or give "
				       "reference.roi, where it is in the "
				       "probe's photo",
				       path);
	c->ref_own |= own;
	return 0;
}

int glint_rig_load(const char *path, struct glint_rig *r)
{
	static const char *const top[] = { "camera",   "bracket",   "roi",
					   "output",   "sensor",    "optics",
					   "sample",   "reference", "board",
					   "sequence", NULL };
	static const char *const cam_keys[] = { "backend", "device", NULL };
	json_t *cam, *br = NULL;
	int ret;

	memset(r, 0, sizeof(*r));
	snprintf(r->path, sizeof(r->path), "%s", path);
	glint_bracket_default_opts(&r->capture.bracket);
	r->output = "captures";
	ret = glint_json_load(path, &r->doc);
	if (ret < 0)
		return ret;
	ret = glint_json_known_keys(path, "", r->doc, top);
	if (!ret)
		ret = glint_json_object(path, "", r->doc, "camera", 1, &cam);
	if (!ret)
		ret = glint_json_known_keys(path, "camera", cam, cam_keys);
	if (!ret)
		ret = glint_json_string(path, "camera", cam, "backend", 1,
					&r->capture.backend);
	if (!ret)
		ret = glint_json_string(path, "camera", cam, "device", 0,
					&r->capture.device);
	if (!ret)
		ret = glint_json_string(path, "", r->doc, "output", 0,
					&r->output);
	if (!ret)
		ret = glint_json_object(path, "", r->doc, "bracket", 0, &br);
	if (!ret && br)
		ret = load_bracket(path, br, &r->capture.bracket);
	if (!ret)
		ret = load_optics(path, r->doc, &r->capture);
	if (!ret)
		ret = load_roi(path, r->doc, &r->capture);
	if (!ret)
		ret = load_reference(path, r->doc, &r->capture);
	if (!ret)
		ret = load_board(path, r);
	if (!ret)
		ret = load_sequence(path, r);
	if (!ret)
		ret = check_reference(path, r);
	if (!ret)
		r->capture.text = json_dumps(r->doc, JSON_INDENT(2));
	return ret;
}

void glint_rig_free(struct glint_rig *r)
{
	free(r->capture.text);
	json_decref(r->doc);
	r->capture.text = NULL;
	r->doc = NULL;
}
