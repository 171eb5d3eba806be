/* SPDX-License-Identifier: MIT */
#ifndef GLINT_BOARD_BOARD_H
#define GLINT_BOARD_BOARD_H

/*
 * The rig's board: GPIO lines by role, behind an ops table (libgpiod v1 in
 * board/gpiod.c, the simulated board in sim/board_sim.c).  Values are
 * logical (1 = pressed / on / enabled); a line's active_low flag is the
 * backend's business.  Nothing here knows about images.
 *
 * What the roles drive (board/board.c):
 *   button            input, both edges, debounced: a press is an edge to
 *                     1 that stays 1 for debounce_s
 *   lights            outputs, the lab lights' relays: one line, or up to
 *                     GLINT_MAX_LIGHTS lines (one per lamp; light 1 is
 *                     GLINT_ROLE_LIGHTS, the others GLINT_ROLE_LIGHTS_2..)
 *   led               output, the status LED, blinked in a pattern per
 *                     state by a thread (glint_board_led)
 *   turntable_step,   outputs of a stepper driver (step pulses at step_hz,
 *   turntable_dir,    direction, enable), or, in relay mode, a relay
 *   turntable_enable  pulsed once per position on turntable_step
 *   position          optional input: 1 when the probe is in view
 *
 * Errors: a negative errno with glint_error_msg() naming the chip, line or
 * role.  Threads: one thread drives a board (the LED thread is the
 * board's own); glint_board_wait_press() may be cancelled from another
 * thread through its flag.  Who frees: glint_board_close() after a
 * successful glint_board_open(); it leaves every output safe.
 */

#include "core/atomic.h"
#include "core/clock.h"
#include "core/error.h"

#include <jansson.h>
#include <stdint.h>

enum glint_role {
	GLINT_ROLE_BUTTON,
	GLINT_ROLE_LIGHTS,
	GLINT_ROLE_LED,
	GLINT_ROLE_TT_STEP,
	GLINT_ROLE_TT_DIR,
	GLINT_ROLE_TT_ENABLE,
	GLINT_ROLE_POSITION,
	GLINT_ROLE_LIGHTS_2, /* "lights[1]": lamp 2, from the rig file's list */
	GLINT_ROLE_LIGHTS_3,
	GLINT_ROLE_LIGHTS_4,
	GLINT_ROLE_COUNT
};

/* Lamps on lines of their own: the rig can capture under each. */
#define GLINT_MAX_LIGHTS 4
/* Light k (1..GLINT_MAX_LIGHTS)'s role. */
enum glint_role glint_role_light(int k);

/* "button", "lights", ..., "lights[1]" (lamp 2), ... as in rig files and
 * messages (static strings); NULL past the end. */
const char *glint_role_name(enum glint_role r);
int glint_role_is_input(enum glint_role r);

struct glint_line_cfg {
	int used;
	char chip[64]; /* "gpiochip0", "/dev/gpiochip0", a number or label */
	char name[64]; /* line name, or "" to use offset */
	int offset;    /* -1 when given by name */
	int active_low;
};

enum glint_turntable_mode { GLINT_TT_NONE, GLINT_TT_STEPPER, GLINT_TT_RELAY };

struct glint_board_cfg {
	char backend[16]; /* "gpiod" or "sim" */
	struct glint_line_cfg lines[GLINT_ROLE_COUNT];
	double debounce_s;
	enum glint_turntable_mode tt_mode;
	int steps_per_turn;	      /* stepper */
	double step_hz;		      /* stepper */
	double relay_pulse_s;	      /* relay */
	double probe_deg, sample_deg; /* turntable positions */
	double reference_deg; /* the gray ball's position (stepper only) */
	double settle_s;      /* wait after a move */
	/* The rig file's "board" object, for the keys only the backend
	 * reads (its ops' cfg_keys); borrowed: valid while the rig file is
	 * loaded, may be NULL.  rig_file names the file in messages and
	 * anchors relative paths in those keys. */
	const json_t *backend_opts;
	const char *rig_file;
	/* A press's deadline, settle times, relay pulses and turntable
	 * steps wait on this clock (NULL: the real one, core/clock.h), and
	 * so do the backend's edge waits (the gpiod backend's kernel waits
	 * move an injected clock by their timeouts); borrowed for the
	 * board's life. */
	const struct glint_clock *clock;
};

void glint_board_default_cfg(struct glint_board_cfg *c);

/* Check a configuration without touching hardware: roles with lines, no
 * line used twice, what the turntable mode needs.  Messages name `file`
 * and the key. */
int glint_board_cfg_check(const char *file, const struct glint_board_cfg *c);

struct glint_edge {
	int value; /* logical level after the edge */
	double t;  /* seconds, CLOCK_MONOTONIC */
};

struct glint_board_ops {
	const char *name;
	/* Keys of the rig file's "board" object that this backend reads from
	 * cfg->backend_opts (NULL-terminated; may be NULL). */
	const char *const *cfg_keys;
	/* Look up every configured line (chip present, line present, free),
	 * then request them: outputs at logical 0.  A failure names chip,
	 * line and, for a busy line, its current consumer; nothing is left
	 * requested. */
	int (*open)(const struct glint_board_cfg *cfg, const char *consumer,
		    void **priv);
	void (*close)(void *priv);
	int (*set)(void *priv, enum glint_role r, int value);
	int (*get)(void *priv, enum glint_role r, int *value);
	/* Next edge on an input within timeout_s: 1 with *e, 0 on timeout. */
	int (*wait_edge)(void *priv, enum glint_role r, double timeout_s,
			 struct glint_edge *e);
	/* Optional: where a requested line was found, for the record (e.g.
	 * `gpiochip0 (glint-rig) line 22 "lights"`). */
	void (*locate)(void *priv, enum glint_role r, char *buf, size_t n);
	/* Optional: the GPIO chip a requested line is on, its name
	 * ("gpiochip1") and label ("pinctrl-bcm2711"); 0 or a negative
	 * errno.  Backends without chips (the simulated board) have none. */
	int (*chip)(void *priv, enum glint_role r, char *name, size_t nn,
		    char *label, size_t nl);
};

/* The real backend (libgpiod v1), when built; the simulated board is
 * sim/'s. */
extern const struct glint_board_ops glint_board_gpiod_ops;

/* The backends glint_board_open() chooses from by cfg->backend: a
 * NULL-terminated list in static storage, set once by the program
 * (cmd/backends.c) before any board is opened. */
void glint_board_backends_set(const struct glint_board_ops *const *list);
/* The registered list, or the backend named `name` (NULL if none). */
const struct glint_board_ops *const *glint_board_backends(void);
const struct glint_board_ops *glint_board_backend(const char *name);

/* LED patterns: idle = a short blink every 2 s, busy = 4 Hz blinking,
 * done = steady on, error = three fast blinks every 1.5 s, off. */
enum glint_led {
	GLINT_LED_OFF,
	GLINT_LED_IDLE,
	GLINT_LED_BUSY,
	GLINT_LED_DONE,
	GLINT_LED_ERROR
};
/* "off", "idle", ...: a static string. */
const char *glint_led_name(enum glint_led l);

struct glint_board;

/* Request the lines cfg names (as `consumer`, shown by gpioinfo): *out
 * is the caller's, closed with glint_board_close().  cfg is copied. */
int glint_board_open(const struct glint_board_cfg *cfg, const char *consumer,
		     struct glint_board **out);
/* Outputs to their safe states (lights off, stepper disabled, LED off),
 * then release every line. */
void glint_board_close(struct glint_board *b);

/* Wait for a debounced press; 1 pressed, 0 timeout (timeout_s < 0:
 * forever) or *cancel set (polled every 50 ms). */
int glint_board_wait_press(struct glint_board *b, double timeout_s,
			   atomic_int *cancel);
int glint_board_has(const struct glint_board *b, enum glint_role r);
/* Where a configured line is on the hardware (the backend's words, or the
 * rig file's chip and line where the backend has none). */
void glint_board_locate(const struct glint_board *b, enum glint_role r,
			char *buf, size_t n);
/* The GPIO chip of a configured line (the backend's chip op): -ENODEV,
 * named, for a backend without chips. */
int glint_board_chip(const struct glint_board *b, enum glint_role r, char *name,
		     size_t nn, char *label, size_t nl);
/* Every light on (1) or off (0). */
int glint_board_lights(struct glint_board *b, int on);
/* Light k (1..) on and every other light off; then the settle wait. */
int glint_board_light_only(struct glint_board *b, int k);
/* How many lights the configuration has lines for (0..GLINT_MAX_LIGHTS):
 * the lights are lights, lights[1], ... in order, none missing. */
int glint_board_cfg_nlights(const struct glint_board_cfg *c);
int glint_board_led(struct glint_board *b, enum glint_led pattern);
/* Where the turntable turns: the probe, the sample, or the gray
 * reference ball (a stepper's third position, reference_deg). */
enum { GLINT_TT_AT_PROBE, GLINT_TT_AT_SAMPLE, GLINT_TT_AT_REFERENCE };
extern const char *const glint_tt_position_names[3];
/* Turn the turntable to position `which` (GLINT_TT_AT_*).  No-op without
 * a turntable; a relay table has no reference position (-EINVAL).
 * *cancel stops between steps (-ECANCELED). */
int glint_board_turntable(struct glint_board *b, int which, atomic_int *cancel);
/* Lights off, stepper disabled: what SIGTERM and errors leave. */
void glint_board_safe(struct glint_board *b);

#endif
