/* SPDX-License-Identifier: MIT */
/*
 * The simulated board (a backend of board/board.h).  Its button is played
 * from a scenario file; every output change is recorded (in memory and as
 * JSON lines in the rig file's board.log) and moves the simulated world
 * (sim/world.h): lights on/off, and the turntable, whose angle follows the step
 * pulses (stepper: steps_per_turn per turn, direction line) or the relay pulses
 * (an indexing table: each pulse goes to the other position).  The sim
 * camera's scene=rig shows what is then in view.
 *
 * Scenario (JSON, sim/scenario.h; the sim camera reads the same file's
 * "camera", and shares the file's world):
 *   {"presses": [{"at_s": 0.5, "hold_s": 0.2, "bounces": 3}, ...]}
 * at_s counts from the board's opening; each press starts with `bounces`
 * extra 2 ms toggles (contact bounce) before the level settles at 1, and
 * is released (0) hold_s later.
 */
#define _POSIX_C_SOURCE 200809L
#include "board_sim.h"
#include "scenario.h"
#include "world.h"

#include "core/clock.h"
#include "core/json.h"
#include "core/path.h"

#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define MAX_EDGES 4096

struct sim_board {
	struct glint_board_cfg cfg;
	char scenario[GLINT_PATH_MAX]; /* board.scenario, resolved; "" none */
	char log_path[GLINT_PATH_MAX]; /* board.log, resolved; "" none */
	double t0;
	struct glint_edge edges[MAX_EDGES]; /* the button's, in time order */
	int nedges, next_edge;
	int out[GLINT_ROLE_COUNT];
	double angle; /* turntable, degrees */
	FILE *log;
	pthread_mutex_t lock;
	/* The world: its scenario's when the scenario also describes the
	 * camera (shared), else that of the cameras without a scenario. */
	struct glint_sim_world *world;
	int shared;
};

/* The board's clock (cfg.clock, NULL: the real one): the scenario's
 * presses are played on it, and waits sleep on it. */
static double now_s(const struct sim_board *s)
{
	return glint_clock_now(s->cfg.clock);
}

static int add_edge(struct sim_board *s, double t, int v)
{
	if (s->nedges == MAX_EDGES)
		return glint_error_set(E2BIG, "%s: more than %d button edges",
				       s->scenario, MAX_EDGES);
	s->edges[s->nedges++] = (struct glint_edge){ v, s->t0 + t };
	return 0;
}

static int load_scenario(struct sim_board *s)
{
	static const char *const keys[] = { "at_s", "hold_s", "bounces", NULL };
	const char *f = s->scenario;
	json_t *doc, *arr;
	int ret;

	if (!f[0])
		return 0;
	ret = glint_sim_scenario_load(f, &doc);
	if (ret < 0)
		return ret;
	arr = json_object_get(doc, "presses"); /* none: never pressed */
	s->shared = json_object_get(doc, "camera") != NULL;
	double last = -1;
	for (size_t i = 0; !ret && i < json_array_size(arr); i++) {
		json_t *p = json_array_get(arr, i);
		char where[32];
		double at = 0, hold = 0.2, bounces = 0;
		snprintf(where, sizeof(where), "presses[%zu]", i);
		ret = glint_json_known_keys(f, where, p, keys);
		if (!ret)
			ret = glint_json_number(
				f, where, p, "at_s", 1,
				(struct glint_range){ 0, 86400, 0, 0 }, &at);
		if (!ret)
			ret = glint_json_number(
				f, where, p, "hold_s", 0,
				(struct glint_range){ 0.001, 60, 0, 0 }, &hold);
		if (!ret)
			ret = glint_json_number(
				f, where, p, "bounces", 0,
				(struct glint_range){ 0, 20, 0, 0 }, &bounces);
		if (!ret && at <= last)
			ret = glint_error_set(EINVAL,
					      "%s: %s.at_s = %g: presses must "
					      "come in time order, after the "
					      "previous release",
					      f, where, at);
		int nb = (int)bounces;
		for (int k = 0; !ret && k < 2 * nb; k++)
			ret = add_edge(s, at + 0.002 * k, !(k & 1));
		if (!ret)
			ret = add_edge(s, at + 0.002 * 2 * nb, 1);
		if (!ret)
			ret = add_edge(s, at + 0.002 * 2 * nb + hold, 0);
		last = at + 0.002 * 2 * nb + hold;
	}
	json_decref(doc);
	return ret;
}

static void update_world(struct sim_board *s)
{
	struct glint_sim_state w;
	const struct glint_board_cfg *c = &s->cfg;
	glint_sim_world_get(s->world, &w);
	/* no lights line: the lab's lamp is always on */
	w.lights = c->lines[GLINT_ROLE_LIGHTS].used ? 0 : 1;
	for (int k = 1; k <= GLINT_MAX_LIGHTS; k++)
		if (c->lines[glint_role_light(k)].used &&
		    s->out[glint_role_light(k)])
			w.lights |= 1u << (k - 1);
	w.turntable_deg = s->angle;
	if (c->tt_mode == GLINT_TT_NONE)
		w.view = GLINT_SIM_VIEW_PROBE;
	else if (fabs(remainder(s->angle - c->probe_deg, 360)) < 1)
		w.view = GLINT_SIM_VIEW_PROBE;
	else if (fabs(remainder(s->angle - c->sample_deg, 360)) < 1)
		w.view = GLINT_SIM_VIEW_SAMPLE;
	else if (fabs(remainder(s->angle - c->reference_deg, 360)) < 1)
		w.view = GLINT_SIM_VIEW_REFERENCE;
	else
		w.view = GLINT_SIM_VIEW_NONE;
	glint_sim_world_set(s->world, &w);
}

/* board.scenario and board.log, relative to the rig file. */
static int load_paths(struct sim_board *s)
{
	static const char *const keys[] = { "scenario", "log" };
	char *out[] = { s->scenario, s->log_path };
	const char *file = s->cfg.rig_file ? s->cfg.rig_file : "rig";

	for (int i = 0; i < 2; i++) {
		const char *v = NULL;
		int ret = glint_json_string(file, "board",
					    (json_t *)s->cfg.backend_opts,
					    keys[i], 0, &v);
		if (ret == 0 && v)
			ret = glint_path_resolve(out[i], GLINT_PATH_MAX, file,
						 v);
		if (ret < 0)
			return ret;
	}
	return 0;
}

static int sim_open(const struct glint_board_cfg *cfg, const char *consumer,
		    void **priv)
{
	struct sim_board *s = calloc(1, sizeof(*s));
	int ret;

	(void)consumer;
	*priv = NULL;
	if (!s)
		return glint_error_set(ENOMEM, "out of memory");
	s->cfg = *cfg;
	s->t0 = now_s(s);
	s->angle = cfg->probe_deg;
	ret = s->cfg.backend_opts ? load_paths(s) : 0;
	if (!ret)
		ret = load_scenario(s);
	if (!ret)
		ret = glint_sim_world_open(s->shared ? s->scenario : NULL,
					   &s->world);
	if (!ret && s->log_path[0]) {
		s->log = fopen(s->log_path, "a");
		if (!s->log)
			ret = glint_error_set(errno, "%s: %s", s->log_path,
					      strerror(errno));
	}
	if (ret < 0) {
		glint_sim_world_close(s->world);
		free(s);
		return glint_error_prefix(ret, "sim board");
	}
	pthread_mutex_init(&s->lock, NULL);
	update_world(s);
	*priv = s;
	return 0;
}

static void sim_close(void *priv)
{
	struct sim_board *s = priv;
	if (!s)
		return;
	if (s->log)
		fclose(s->log);
	pthread_mutex_destroy(&s->lock);
	glint_sim_world_reset(s->world);
	glint_sim_world_close(s->world);
	free(s);
}

static int sim_set(void *priv, enum glint_role r, int v)
{
	struct sim_board *s = priv;
	const struct glint_board_cfg *c = &s->cfg;

	pthread_mutex_lock(&s->lock);
	int was = s->out[r];
	s->out[r] = v;
	if (r == GLINT_ROLE_TT_STEP && v && !was) {
		if (c->tt_mode == GLINT_TT_STEPPER &&
		    (!c->lines[GLINT_ROLE_TT_ENABLE].used ||
		     s->out[GLINT_ROLE_TT_ENABLE]))
			s->angle +=
				(s->out[GLINT_ROLE_TT_DIR] ? 360.0 : -360.0) /
				c->steps_per_turn;
		else if (c->tt_mode == GLINT_TT_RELAY)
			s->angle = fabs(remainder(s->angle - c->probe_deg,
						  360)) < 1
					   ? c->sample_deg
					   : c->probe_deg;
	}
	if (s->log && was != v) {
		fprintf(s->log,
			"{\"t\": %.4f, \"line\": \"%s\", \"value\": %d, "
			"\"turntable_deg\": %.3f}\n",
			now_s(s) - s->t0, glint_role_name(r), v, s->angle);
		fflush(s->log);
	}
	update_world(s);
	pthread_mutex_unlock(&s->lock);
	return 0;
}

static int level_at(const struct sim_board *s, double t)
{
	int v = 0;
	for (int i = 0; i < s->nedges && s->edges[i].t <= t; i++)
		v = s->edges[i].value;
	return v;
}

static int sim_get(void *priv, enum glint_role r, int *v)
{
	struct sim_board *s = priv;
	pthread_mutex_lock(&s->lock);
	if (r == GLINT_ROLE_BUTTON)
		*v = level_at(s, now_s(s));
	else if (r == GLINT_ROLE_POSITION) /* 1: the probe faces the camera */
		*v = fabs(remainder(s->angle - s->cfg.probe_deg, 360)) < 1;
	else
		*v = s->out[r];
	pthread_mutex_unlock(&s->lock);
	return 0;
}

static int sim_wait_edge(void *priv, enum glint_role r, double timeout_s,
			 struct glint_edge *e)
{
	struct sim_board *s = priv;
	double t_end = now_s(s) + timeout_s;

	if (r != GLINT_ROLE_BUTTON)
		return 0; /* the position sensor never moves by itself */
	int got = 0;
	pthread_mutex_lock(&s->lock);
	int i = s->next_edge;
	if (i < s->nedges && s->edges[i].t <= t_end) {
		*e = s->edges[i];
		s->next_edge++;
		got = 1;
	}
	pthread_mutex_unlock(&s->lock);
	double until = got ? e->t : t_end;
	double dt = until - now_s(s);
	glint_clock_sleep(s->cfg.clock, dt);
	return got;
}

static const char *const sim_cfg_keys[] = { "scenario", "log", NULL };

const struct glint_board_ops glint_board_sim_ops = {
	.name = "sim",
	.cfg_keys = sim_cfg_keys,
	.open = sim_open,
	.close = sim_close,
	.set = sim_set,
	.get = sim_get,
	.wait_edge = sim_wait_edge,
};
