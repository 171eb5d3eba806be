/* SPDX-License-Identifier: MIT */
/*
 * The board by role over a backend's lines: debounced presses, the LED's
 * patterns (a thread), the turntable's moves, safe states.
 */
#define _POSIX_C_SOURCE 200809L
#include "board.h"

#include "core/clock.h"
#include "core/log.h"

#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static const char *const role_names[GLINT_ROLE_COUNT] = {
	"button",	 "lights",	     "led",	 "turntable_step",
	"turntable_dir", "turntable_enable", "position", "lights[1]",
	"lights[2]",	 "lights[3]",
};

enum glint_role glint_role_light(int k)
{
	return k <= 1 ? GLINT_ROLE_LIGHTS
		      : (enum glint_role)(GLINT_ROLE_LIGHTS_2 + k - 2);
}

int glint_board_cfg_nlights(const struct glint_board_cfg *c)
{
	int n = 0;
	while (n < GLINT_MAX_LIGHTS && c->lines[glint_role_light(n + 1)].used)
		n++;
	return n;
}

const char *glint_role_name(enum glint_role r)
{
	return (unsigned)r < GLINT_ROLE_COUNT ? role_names[r] : NULL;
}

int glint_role_is_input(enum glint_role r)
{
	return r == GLINT_ROLE_BUTTON || r == GLINT_ROLE_POSITION;
}

const char *glint_led_name(enum glint_led l)
{
	static const char *const n[] = { "off", "idle", "busy", "done",
					 "error" };
	return (unsigned)l < 5 ? n[l] : "?";
}

void glint_board_default_cfg(struct glint_board_cfg *c)
{
	memset(c, 0, sizeof(*c));
	snprintf(c->backend, sizeof(c->backend), "sim");
	for (int r = 0; r < GLINT_ROLE_COUNT; r++)
		c->lines[r].offset = -1;
	c->debounce_s = 0.03;
	c->steps_per_turn = 3200;
	c->step_hz = 1600;
	c->relay_pulse_s = 0.2;
	c->probe_deg = 0;
	c->sample_deg = 180;
	c->reference_deg = 90;
	c->settle_s = 0.2;
}

static int same_line(const struct glint_line_cfg *a,
		     const struct glint_line_cfg *b)
{
	if (strcmp(a->chip, b->chip) != 0)
		return 0;
	if (a->name[0] || b->name[0])
		return !strcmp(a->name, b->name);
	return a->offset == b->offset;
}

static const struct glint_board_ops *const no_backends[] = { NULL };
static const struct glint_board_ops *const *registered = no_backends;

void glint_board_backends_set(const struct glint_board_ops *const *list)
{
	registered = list ? list : no_backends;
}

const struct glint_board_ops *const *glint_board_backends(void)
{
	return registered;
}

const struct glint_board_ops *glint_board_backend(const char *name)
{
	for (int i = 0; registered[i]; i++)
		if (!strcmp(registered[i]->name, name))
			return registered[i];
	return NULL;
}

/* "gpiod or sim": the registered backends' names, for messages. */
static void backend_names(char *buf, size_t n)
{
	buf[0] = 0;
	for (int i = 0; registered[i]; i++) {
		size_t len = strlen(buf);
		snprintf(buf + len, n - len, "%s%s",
			 !i		     ? ""
			 : registered[i + 1] ? ", "
					     : " or ",
			 registered[i]->name);
	}
}

int glint_board_cfg_check(const char *file, const struct glint_board_cfg *c)
{
	const struct glint_line_cfg *l = c->lines;
	char names[128];

	backend_names(names, sizeof(names));
	/* "gpiod" is a valid rig file on a glint built without libgpiod:
	 * opening the board says what is missing. */
	if (!glint_board_backend(c->backend) && strcmp(c->backend, "gpiod"))
		return glint_error_set(EINVAL,
				       "%s: board.backend = \"%s\": expected "
				       "%s",
				       file, c->backend, names);
	if (!l[GLINT_ROLE_BUTTON].used)
		return glint_error_set(EINVAL,
				       "%s: board.lines.button: missing (the "
				       "rig needs its capture button)",
				       file);
	for (int a = 0; a < GLINT_ROLE_COUNT; a++)
		for (int b = a + 1; b < GLINT_ROLE_COUNT; b++)
			if (l[a].used && l[b].used && same_line(&l[a], &l[b]))
				return glint_error_set(
					EINVAL,
					"%s: board.lines.%s and "
					"board.lines.%s are the same line "
					"(%s %s%.0d): one line per role",
					file, role_names[a], role_names[b],
					l[a].chip, l[a].name,
					l[a].name[0] ? 0 : l[a].offset);
	for (int k = glint_board_cfg_nlights(c) + 2; k <= GLINT_MAX_LIGHTS; k++)
		if (l[glint_role_light(k)].used)
			return glint_error_set(
				EINVAL,
				"%s: board.lines.%s without "
				"board.lines.%s: the lights are "
				"numbered from 1, none missing",
				file, role_names[glint_role_light(k)],
				role_names[glint_role_light(k - 1)]);
	if (c->tt_mode == GLINT_TT_STEPPER &&
	    (!l[GLINT_ROLE_TT_STEP].used || !l[GLINT_ROLE_TT_DIR].used))
		return glint_error_set(EINVAL,
				       "%s: board.turntable.mode = \"stepper\" "
				       "needs board.lines.turntable_step and "
				       "turntable_dir",
				       file);
	if (c->tt_mode == GLINT_TT_RELAY && !l[GLINT_ROLE_TT_STEP].used)
		return glint_error_set(EINVAL,
				       "%s: board.turntable.mode = \"relay\" "
				       "needs board.lines.turntable_step (the "
				       "relay)",
				       file);
	if (c->tt_mode == GLINT_TT_NONE &&
	    (l[GLINT_ROLE_TT_STEP].used || l[GLINT_ROLE_TT_DIR].used ||
	     l[GLINT_ROLE_TT_ENABLE].used))
		return glint_error_set(EINVAL,
				       "%s: board.lines has turntable lines "
				       "but no board.turntable.mode (stepper "
				       "or relay)",
				       file);
	return 0;
}

struct glint_board {
	const struct glint_board_ops *ops;
	void *priv;
	struct glint_board_cfg cfg;
	pthread_mutex_t lock; /* serialises ops calls */
	pthread_cond_t led_cond;
	pthread_t led_thread;
	int led_running, led_stop;
	enum glint_led led;
	double angle_deg; /* where the turntable is believed to be */
	int tt_known;
};

/* The LED thread runs on the host's monotonic clock (a condition
 * variable's timed wait does); a press's deadline, settle times, relay
 * pulses and turntable steps on the board's clock (cfg.clock), which a
 * test fakes: the backend's edge waits run on it (the gpiod backend's
 * kernel waits on the real one, which it is given). */
static double now_s(void)
{
	return glint_clock_monotonic();
}

static int set_line(struct glint_board *b, enum glint_role r, int v)
{
	if (!b->cfg.lines[r].used)
		return 0;
	pthread_mutex_lock(&b->lock);
	int ret = b->ops->set(b->priv, r, v);
	pthread_mutex_unlock(&b->lock);
	return ret;
}

/* On/off steps of each pattern in seconds, repeated; {0} = steady. */
static void led_steps(enum glint_led p, const double **steps, int *n, int *on)
{
	static const double idle[] = { 0.1, 1.9 }, busy[] = { 0.125, 0.125 },
			    error[] = { 0.1, 0.1, 0.1, 0.1, 0.1, 1.0 };
	*steps = NULL;
	*n = 0;
	*on = p == GLINT_LED_DONE;
	if (p == GLINT_LED_IDLE) {
		*steps = idle;
		*n = 2;
	} else if (p == GLINT_LED_BUSY) {
		*steps = busy;
		*n = 2;
	} else if (p == GLINT_LED_ERROR) {
		*steps = error;
		*n = 6;
	}
}

static void *led_main(void *arg)
{
	struct glint_board *b = arg;
	enum glint_led cur = (enum glint_led) - 1;
	int k = 0;
	double next = 0;

	pthread_mutex_lock(&b->lock);
	while (!b->led_stop) {
		const double *steps;
		int n, on;
		led_steps(b->led, &steps, &n, &on);
		if (b->led != cur) {
			cur = b->led;
			k = 0;
			next = now_s();
			if (!n)
				b->ops->set(b->priv, GLINT_ROLE_LED, on);
		}
		if (n && now_s() >= next) {
			b->ops->set(b->priv, GLINT_ROLE_LED, !(k & 1));
			next += steps[k % n];
			k = (k + 1) % n;
		}
		double wake = n ? next : now_s() + 3600;
		struct timespec ts;
		clock_gettime(CLOCK_MONOTONIC, &ts);
		double dt = wake - now_s();
		if (dt > 0) {
			ts.tv_sec += (time_t)dt;
			ts.tv_nsec += (long)((dt - floor(dt)) * 1e9);
			if (ts.tv_nsec >= 1000000000L) {
				ts.tv_sec++;
				ts.tv_nsec -= 1000000000L;
			}
			pthread_cond_timedwait(&b->led_cond, &b->lock, &ts);
		}
	}
	pthread_mutex_unlock(&b->lock);
	return NULL;
}

int glint_board_open(const struct glint_board_cfg *cfg, const char *consumer,
		     struct glint_board **out)
{
	struct glint_board *b;
	const struct glint_board_ops *ops = NULL;
	int ret;

	*out = NULL;
	ops = glint_board_backend(cfg->backend);
	if (!ops) {
		char names[128];
		backend_names(names, sizeof(names));
		return glint_error_set(
			EINVAL, "board backend '%s': this glint has %s%s",
			cfg->backend, names,
			strcmp(cfg->backend, "gpiod")
				? ""
				: " (built without libgpiod)");
	}
	b = calloc(1, sizeof(*b));
	if (!b)
		return glint_error_set(ENOMEM, "out of memory");
	b->ops = ops;
	b->cfg = *cfg;
	ret = ops->open(cfg, consumer, &b->priv);
	if (ret < 0) {
		free(b);
		return ret;
	}
	pthread_mutex_init(&b->lock, NULL);
	pthread_condattr_t ca;
	pthread_condattr_init(&ca);
	pthread_condattr_setclock(&ca, CLOCK_MONOTONIC);
	pthread_cond_init(&b->led_cond, &ca);
	pthread_condattr_destroy(&ca);
	if (cfg->lines[GLINT_ROLE_LED].used &&
	    pthread_create(&b->led_thread, NULL, led_main, b) == 0)
		b->led_running = 1;
	*out = b;
	return 0;
}

void glint_board_safe(struct glint_board *b)
{
	if (!b)
		return;
	for (int k = 1; k <= GLINT_MAX_LIGHTS; k++)
		set_line(b, glint_role_light(k), 0);
	set_line(b, GLINT_ROLE_TT_STEP, 0);
	set_line(b, GLINT_ROLE_TT_ENABLE, 0);
}

void glint_board_close(struct glint_board *b)
{
	if (!b)
		return;
	glint_board_safe(b);
	if (b->led_running) {
		pthread_mutex_lock(&b->lock);
		b->led_stop = 1;
		pthread_cond_signal(&b->led_cond);
		pthread_mutex_unlock(&b->lock);
		pthread_join(b->led_thread, NULL);
	}
	set_line(b, GLINT_ROLE_LED, 0);
	b->ops->close(b->priv);
	pthread_mutex_destroy(&b->lock);
	pthread_cond_destroy(&b->led_cond);
	free(b);
}

int glint_board_has(const struct glint_board *b, enum glint_role r)
{
	return b && b->cfg.lines[r].used;
}

void glint_board_locate(const struct glint_board *b, enum glint_role r,
			char *buf, size_t n)
{
	const struct glint_line_cfg *l = &b->cfg.lines[r];

	if (b->ops->locate) {
		pthread_mutex_lock((pthread_mutex_t *)&b->lock);
		b->ops->locate(b->priv, r, buf, n);
		pthread_mutex_unlock((pthread_mutex_t *)&b->lock);
	} else if (l->name[0]) {
		snprintf(buf, n, "%s line \"%s\"", l->chip, l->name);
	} else {
		snprintf(buf, n, "%s line %d", l->chip, l->offset);
	}
}

int glint_board_chip(const struct glint_board *b, enum glint_role r, char *name,
		     size_t nn, char *label, size_t nl)
{
	if (!b->cfg.lines[r].used)
		return glint_error_set(ENOENT, "board: no %s line",
				       glint_role_name(r));
	if (!b->ops->chip)
		return glint_error_set(
			ENODEV,
			"board: the %s backend's lines are on no "
			"GPIO chip",
			b->ops->name);
	pthread_mutex_lock((pthread_mutex_t *)&b->lock);
	int ret = b->ops->chip(b->priv, r, name, nn, label, nl);
	pthread_mutex_unlock((pthread_mutex_t *)&b->lock);
	return ret;
}

int glint_board_led(struct glint_board *b, enum glint_led pattern)
{
	if (!b->led_running)
		return 0;
	glint_log_info("led: %s", glint_led_name(pattern));
	pthread_mutex_lock(&b->lock);
	b->led = pattern;
	pthread_cond_signal(&b->led_cond);
	pthread_mutex_unlock(&b->lock);
	return 0;
}

/* Light k on where mask has bit k - 1; the settle wait if any line
 * moved. */
static int lights_set(struct glint_board *b, unsigned mask)
{
	int ret = 0, any = 0;
	/* off first: two lamps never on together by accident */
	for (int pass = 0; pass < 2; pass++)
		for (int k = 1; k <= GLINT_MAX_LIGHTS && ret == 0; k++) {
			int on = (mask >> (k - 1)) & 1;
			if (on != pass ||
			    !b->cfg.lines[glint_role_light(k)].used)
				continue;
			ret = set_line(b, glint_role_light(k), on);
			any = 1;
		}
	if (ret == 0 && any)
		glint_clock_sleep(b->cfg.clock,
				  b->cfg.settle_s); /* lamps warm up */
	return ret;
}

int glint_board_lights(struct glint_board *b, int on)
{
	return lights_set(b, on ? ~0u : 0);
}

int glint_board_light_only(struct glint_board *b, int k)
{
	int n = glint_board_cfg_nlights(&b->cfg);
	if (k < 1 || k > n)
		return glint_error_set(EINVAL,
				       "light %d: the board has %d light "
				       "line%s",
				       k, n, n == 1 ? "" : "s");
	return lights_set(b, 1u << (k - 1));
}

/* Edges come in while the line bounces; the press counts when the level
 * is still 1 once no edge has come for debounce_s. */
int glint_board_wait_press(struct glint_board *b, double timeout_s,
			   atomic_int *cancel)
{
	const struct glint_clock *clk = b->cfg.clock;
	double t_end =
		timeout_s < 0 ? INFINITY : glint_clock_now(clk) + timeout_s;
	struct glint_edge e;

	for (;;) {
		if (cancel && *cancel)
			return 0;
		double left = t_end - glint_clock_now(clk);
		if (left <= 0)
			return 0;
		int ret = b->ops->wait_edge(b->priv, GLINT_ROLE_BUTTON,
					    fmin(left, 0.05), &e);
		if (ret < 0)
			return ret;
		if (ret == 0 || e.value != 1)
			continue;
		/* Settle: every further edge restarts the window. */
		int level = 1;
		for (;;) {
			ret = b->ops->wait_edge(b->priv, GLINT_ROLE_BUTTON,
						b->cfg.debounce_s, &e);
			if (ret < 0)
				return ret;
			if (ret == 0)
				break;
			level = e.value;
		}
		if (level == 1)
			return 1;
	}
}

const char *const glint_tt_position_names[3] = { "probe", "sample",
						 "reference" };

int glint_board_turntable(struct glint_board *b, int which, atomic_int *cancel)
{
	const struct glint_board_cfg *c = &b->cfg;
	double target = which == GLINT_TT_AT_SAMPLE	 ? c->sample_deg
			: which == GLINT_TT_AT_REFERENCE ? c->reference_deg
							 : c->probe_deg;
	int ret = 0;

	if (which < 0 || which > GLINT_TT_AT_REFERENCE)
		return glint_error_set(EINVAL, "turntable: position %d", which);
	if (c->tt_mode == GLINT_TT_NONE)
		return 0;
	if (c->tt_mode == GLINT_TT_RELAY && which == GLINT_TT_AT_REFERENCE)
		return glint_error_set(EINVAL,
				       "turntable: a relay (indexing) table "
				       "has two positions, probe and sample: "
				       "the reference ball needs a stepper "
				       "(board.turntable.mode \"stepper\") "
				       "or its own frame beside the probe "
				       "(reference.roi)");
	if (c->tt_mode == GLINT_TT_RELAY) {
		/* An indexing table: one pulse moves it to the next of its
		 * two positions. */
		if (b->tt_known && fabs(b->angle_deg - target) < 1e-9)
			return 0;
		ret = set_line(b, GLINT_ROLE_TT_STEP, 1);
		glint_clock_sleep(b->cfg.clock, c->relay_pulse_s);
		if (!ret)
			ret = set_line(b, GLINT_ROLE_TT_STEP, 0);
	} else {
		double from = b->tt_known ? b->angle_deg : c->probe_deg;
		double d = remainder(target - from, 360.0);
		long steps = lround(fabs(d) / 360.0 * c->steps_per_turn);
		double half = 0.5 / c->step_hz;
		ret = set_line(b, GLINT_ROLE_TT_ENABLE, 1);
		if (!ret)
			ret = set_line(b, GLINT_ROLE_TT_DIR, d >= 0);
		for (long i = 0; i < steps && !ret; i++) {
			if (cancel && *cancel) {
				ret = glint_error_set(ECANCELED,
						      "turntable move "
						      "cancelled");
				break;
			}
			ret = set_line(b, GLINT_ROLE_TT_STEP, 1);
			glint_clock_sleep(b->cfg.clock, half);
			if (!ret)
				ret = set_line(b, GLINT_ROLE_TT_STEP, 0);
			glint_clock_sleep(b->cfg.clock, half);
		}
		/* Enable stays on to hold position while capturing. */
	}
	if (ret < 0) {
		b->tt_known = 0;
		return ret;
	}
	b->angle_deg = target;
	b->tt_known = 1;
	glint_clock_sleep(b->cfg.clock, c->settle_s);
	/* With a position sensor, trust it over the step count. */
	if (c->lines[GLINT_ROLE_POSITION].used) {
		int at_probe = 0;
		pthread_mutex_lock(&b->lock);
		ret = b->ops->get(b->priv, GLINT_ROLE_POSITION, &at_probe);
		pthread_mutex_unlock(&b->lock);
		if (ret < 0)
			return ret;
		if (at_probe != (which == GLINT_TT_AT_PROBE)) {
			b->tt_known = 0;
			return glint_error_set(EIO,
					       "turntable: moved to the %s but "
					       "the position sensor "
					       "(board.lines.position) reads "
					       "%d: stalled or slipped?",
					       glint_tt_position_names[which],
					       at_probe);
		}
	}
	glint_log_info("turntable at %s (%.0f deg)",
		       glint_tt_position_names[which], target);
	return 0;
}
