/* SPDX-License-Identifier: MIT */
/*
 * The libgpiod board backend against the fake GPIO chip
 * (tests/fake_gpio, LD_PRELOADed): requests, values (active-low
 * included), debounced edge events, a busy line, a line out of range or
 * unknown by name, a missing chip, a chip that vanishes.
 */
#define _POSIX_C_SOURCE 200809L
#include "cmd/backends.h"
#include "test.h"

#include "board/board.h"
#include "core/clock.h"
#include "sim/world.h"
#include "core/error.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static char logpath[256];

static void cfg_default(struct glint_board_cfg *c)
{
	glint_board_default_cfg(c);
	snprintf(c->backend, sizeof(c->backend), "gpiod");
	const struct {
		enum glint_role r;
		int off, al;
	} map[] = { { GLINT_ROLE_BUTTON, 17, 1 },
		    { GLINT_ROLE_LIGHTS, 22, 0 },
		    { GLINT_ROLE_TT_STEP, 23, 0 },
		    { GLINT_ROLE_TT_DIR, 24, 0 },
		    { GLINT_ROLE_TT_ENABLE, 25, 1 } };
	for (size_t i = 0; i < sizeof(map) / sizeof(map[0]); i++) {
		struct glint_line_cfg *l = &c->lines[map[i].r];
		l->used = 1;
		snprintf(l->chip, sizeof(l->chip), "gpiochip0");
		l->offset = map[i].off;
		l->active_low = map[i].al;
	}
	c->tt_mode = GLINT_TT_STEPPER;
	c->steps_per_turn = 40;
	c->step_hz = 4000;
	c->settle_s = 0;
}

static void fake(const char *opts)
{
	char env[512];
	snprintf(env, sizeof(env), "log=%s%s%s", logpath, opts[0] ? "," : "",
		 opts);
	setenv("FAKE_GPIO", env, 1);
}

/* Last logged logical and physical values of an offset; -1 if never. */
static void last_value(unsigned off, int *value, int *phys, int *changes)
{
	char line[512];
	FILE *f = fopen(logpath, "r");
	*value = *phys = -1;
	*changes = 0;
	if (!f)
		return;
	while (fgets(line, sizeof(line), f)) {
		unsigned o;
		int v, p;
		if (sscanf(line,
			   "{\"t\": %*f, \"offset\": %u, \"value\": %d, "
			   "\"phys\": %d",
			   &o, &v, &p) == 3 &&
		    o == off) {
			*value = v;
			*phys = p;
			(*changes)++;
		}
	}
	fclose(f);
}

static void test_outputs(void)
{
	struct glint_board_cfg c;
	struct glint_board *b;
	int v, p, n;
	cfg_default(&c);
	fake("");
	CHECK(glint_board_open(&c, "glint test", &b) == 0, "%s",
	      glint_error_msg());
	if (!b)
		return;
	/* Safe from the first instant: each output is requested
	 * at its inactive value, with no later write needed. */
	last_value(22, &v, &p, &n);
	CHECK(v == 0 && n == 1, "lights at open: %d after %d changes", v, n);
	last_value(25, &v, &p, &n);
	CHECK(v == 0 && p == 1 && n == 1,
	      "active-low enable at open: logical %d, physical %d", v, p);
	CHECK(glint_board_lights(b, 1) == 0, "%s", glint_error_msg());
	last_value(22, &v, &p, &n);
	CHECK(v == 1 && p == 1, "lights on: logical %d physical %d", v, p);
	CHECK(glint_board_turntable(b, 1, NULL) == 0, "%s", glint_error_msg());
	last_value(25, &v, &p, &n);
	CHECK(v == 1 && p == 0,
	      "active-low enable on: logical %d, physical %d (expected 1, 0)",
	      v, p);
	last_value(23, &v, &p, &n);
	/* Half a turn of 40 steps: 20 pulses = 40 changes (after the
	 * request's initial 0). */
	CHECK(n == 1 + 40, "step line changes %d, expected 41", n);
	glint_board_close(b);
	last_value(22, &v, &p, &n);
	CHECK(v == 0, "lights off after close: %d", v);
	last_value(25, &v, &p, &n);
	CHECK(v == 0 && p == 1, "stepper disabled after close: %d/%d", v, p);
}

static void test_press(void)
{
	struct glint_board_cfg c;
	struct glint_board *b;
	cfg_default(&c);
	fake("press=0.2:0.1:3;0.6:0.15:0");
	CHECK(glint_board_open(&c, "glint test", &b) == 0, "%s",
	      glint_error_msg());
	if (!b)
		return;
	int r1 = glint_board_wait_press(b, 2, NULL);
	int r2 = glint_board_wait_press(b, 2, NULL);
	int r3 = glint_board_wait_press(b, 0.5, NULL);
	CHECK(r1 == 1 && r2 == 1 && r3 == 0,
	      "two presses (one bouncing), then none: %d %d %d", r1, r2, r3);
	glint_board_close(b);
}

static void expect_open_error(const char *opts, struct glint_board_cfg *c,
			      const char *const frags[])
{
	struct glint_board *b = NULL;
	fake(opts);
	remove(logpath);
	int ret = glint_board_open(c, "glint test", &b);
	CHECK(ret < 0 && !b, "open should fail (%s)", opts);
	for (int i = 0; frags[i]; i++)
		CHECK_MSG(glint_error_msg(), frags[i]);
	int v, p, n;
	last_value(22, &v, &p, &n);
	CHECK(n == 0, "no output touched on a refused open (%d changes)", n);
	glint_board_close(b);
}

static void test_refusals(void)
{
	struct glint_board_cfg c;
	cfg_default(&c);
	expect_open_error("busy=22:pigpiod", &c,
			  (const char *const[]){ "lights", "gpiochip0", "22",
						 "busy", "pigpiod", NULL });
	cfg_default(&c);
	c.lines[GLINT_ROLE_LIGHTS].offset = 40;
	expect_open_error("", &c,
			  (const char *const[]){ "lights", "out of range",
						 "0..31", NULL });
	cfg_default(&c);
	snprintf(c.lines[GLINT_ROLE_LIGHTS].name,
		 sizeof(c.lines[GLINT_ROLE_LIGHTS].name), "RELAY9");
	expect_open_error("", &c,
			  (const char *const[]){ "RELAY9",
						 "no line of that "
						 "name",
						 NULL });
	cfg_default(&c);
	snprintf(c.lines[GLINT_ROLE_LIGHTS].chip,
		 sizeof(c.lines[GLINT_ROLE_LIGHTS].chip), "gpiochip7");
	expect_open_error("", &c,
			  (const char *const[]){ "gpiochip7",
						 "no such GPIO "
						 "chip",
						 NULL });
	/* By name works. */
	struct glint_board *b = NULL;
	cfg_default(&c);
	snprintf(c.lines[GLINT_ROLE_LIGHTS].name,
		 sizeof(c.lines[GLINT_ROLE_LIGHTS].name), "GPIO22");
	fake("");
	CHECK(glint_board_open(&c, "glint test", &b) == 0, "by name: %s",
	      glint_error_msg());
	glint_board_close(b);
}

static void test_vanish(void)
{
	struct glint_board_cfg c;
	struct glint_board *b = NULL;
	cfg_default(&c);
	fake("vanish_after=40");
	CHECK(glint_board_open(&c, "glint test", &b) == 0, "%s",
	      glint_error_msg());
	if (!b)
		return;
	int ret = 0;
	for (int i = 0; i < 100 && ret == 0; i++)
		ret = glint_board_lights(b, i & 1);
	CHECK(ret < 0, "setting a line on a vanished chip must fail");
	CHECK_MSG(glint_error_msg(), "disappeared");
	CHECK_MSG(glint_error_msg(), "lights");
	glint_board_close(b); /* must not crash or hang */
}

/* A position sensor that disagrees with the step count is an error (the
 * fake's inputs read 0: "probe not in view"). */
static void test_position_sensor(void)
{
	struct glint_board_cfg c;
	struct glint_board *b = NULL;
	cfg_default(&c);
	c.lines[GLINT_ROLE_POSITION].used = 1;
	snprintf(c.lines[GLINT_ROLE_POSITION].chip,
		 sizeof(c.lines[GLINT_ROLE_POSITION].chip), "gpiochip0");
	c.lines[GLINT_ROLE_POSITION].offset = 5;
	fake("");
	CHECK(glint_board_open(&c, "glint test", &b) == 0, "%s",
	      glint_error_msg());
	if (!b)
		return;
	CHECK(glint_board_turntable(b, 1, NULL) == 0, "to the sample: %s",
	      glint_error_msg());
	CHECK(glint_board_turntable(b, 0, NULL) < 0,
	      "to the probe with the sensor reading 0 must fail");
	CHECK_MSG(glint_error_msg(), "position sensor");
	glint_board_close(b);
}

/* The board's waits are on its injected clock: an hour's settle time
 * and 40 steps at 2 Hz (20 s) pass at once on a fake clock, which moves
 * by exactly what the board waited (the real clock barely moves). */
static void test_fake_clock(void)
{
	struct glint_board_cfg c;
	struct glint_board *b;
	struct glint_fake_clock fc = { 100 };
	struct glint_clock clk = glint_clock_fake(&fc);
	cfg_default(&c);
	c.settle_s = 3600;
	c.step_hz = 2;
	c.clock = &clk;
	fake("");
	CHECK(glint_board_open(&c, "glint test", &b) == 0, "%s",
	      glint_error_msg());
	if (!b)
		return;
	double t0 = glint_clock_monotonic();
	CHECK(glint_board_turntable(b, 1, NULL) == 0, "%s", glint_error_msg());
	double real = glint_clock_monotonic() - t0;
	CHECK(fc.t >= 100 + 3600 + 9.9 && fc.t <= 100 + 3600 + 20.1,
	      "fake clock at %.3f after a 3600 s settle and 20 steps at 2 Hz",
	      fc.t);
	CHECK(real < 5, "the move took %.2f s of real time", real);
	glint_board_close(b);
}

/*
 * The sim board on a scenario that also describes the camera: its presses
 * are played on the board's (fake) clock, and its lights move the
 * scenario's world (sim/world.h), not the world of cameras without a
 * scenario.
 */
static void test_sim_board_scenario(void)
{
	struct glint_board_cfg c;
	struct glint_board *b = NULL;
	struct glint_fake_clock fc = { 50 };
	struct glint_clock clk = glint_clock_fake(&fc);
	struct glint_sim_world *w = NULL, *none = NULL;
	struct glint_sim_state st, st0;
	char path[64];
	snprintf(path, sizeof(path), "/tmp/glint-board-scenario-%d.json",
		 (int)getpid());
	FILE *f = fopen(path, "w");
	if (f) {
		fputs("{\"camera\": {\"scene\": \"rig\"}, \"presses\": "
		      "[{\"at_s\": 30, \"hold_s\": 0.5}]}\n",
		      f);
		fclose(f);
	}
	cfg_default(&c);
	snprintf(c.backend, sizeof(c.backend), "sim");
	c.clock = &clk;
	json_t *opts = json_pack("{s:s}", "scenario", path);
	c.backend_opts = opts;
	CHECK(glint_board_open(&c, "glint test", &b) == 0, "%s",
	      glint_error_msg());
	CHECK(glint_sim_world_open(path, &w) == 0 &&
		      glint_sim_world_open(NULL, &none) == 0,
	      "%s", glint_error_msg());
	if (b && w && none) {
		double t0 = glint_clock_monotonic();
		int got = glint_board_wait_press(b, 120, NULL);
		double real = glint_clock_monotonic() - t0;
		CHECK(got == 1 && fc.t >= 50 + 30 && fc.t < 50 + 32,
		      "press %d at fake %.3f s (%.2f s real)", got, fc.t, real);
		CHECK(real < 5, "30 s of presses took %.2f s of real time",
		      real);
		CHECK(glint_board_lights(b, 0) == 0, "%s", glint_error_msg());
		glint_sim_world_get(w, &st);
		glint_sim_world_get(none, &st0);
		CHECK(st.lights == 0 && st0.lights == 1,
		      "lights off: the scenario's world %u, the other %u",
		      st.lights, st0.lights);
	}
	glint_board_close(b);
	glint_sim_world_close(w);
	glint_sim_world_close(none);
	json_decref(opts);
	remove(path);
}

int main(void)
{
	glint_backends_register();
	snprintf(logpath, sizeof(logpath), "/tmp/glint-fake-gpio-%ld.log",
		 (long)getpid());
	if (!getenv("LD_PRELOAD")) {
		fprintf(stderr, "needs the fake GPIO chip preloaded\n");
		return 77;
	}
	RUN(test_outputs);
	RUN(test_press);
	RUN(test_refusals);
	RUN(test_vanish);
	RUN(test_position_sensor);
	RUN(test_fake_clock);
	RUN(test_sim_board_scenario);
	remove(logpath);
	return test_result();
}
