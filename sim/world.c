/* SPDX-License-Identifier: MIT */
#define _DEFAULT_SOURCE /* realpath() */
#include "world.h"

#include "core/error.h"
#include "core/path.h"

#include <limits.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct glint_sim_world {
	char key[GLINT_PATH_MAX]; /* the scenario's real path, "" none */
	int refs;
	pthread_mutex_t lock;
	struct glint_sim_state st;
	struct glint_sim_world *next;
};

/* The worlds open now, by scenario: where the simulators of one scenario
 * find each other. */
static pthread_mutex_t registry_lock = PTHREAD_MUTEX_INITIALIZER;
static struct glint_sim_world *registry;

static const struct glint_sim_state no_board = { 1, GLINT_SIM_VIEW_PROBE, 0 };

int glint_sim_world_open(const char *scenario, struct glint_sim_world **out)
{
	char key[GLINT_PATH_MAX] = "";
	struct glint_sim_world *w;

	*out = NULL;
	if (scenario && scenario[0]) {
		char *real = realpath(scenario, NULL);
		int n = snprintf(key, sizeof(key), "%s",
				 real ? real : scenario);
		free(real);
		if (n < 0 || (size_t)n >= sizeof(key))
			return glint_error_set(ENAMETOOLONG,
					       "%s: scenario path too long",
					       scenario);
	}
	pthread_mutex_lock(&registry_lock);
	for (w = registry; w && strcmp(w->key, key); w = w->next) {
	}
	if (w) {
		w->refs++;
	} else if ((w = calloc(1, sizeof(*w)))) {
		memcpy(w->key, key, sizeof(key));
		w->refs = 1;
		w->st = no_board;
		pthread_mutex_init(&w->lock, NULL);
		w->next = registry;
		registry = w;
	}
	pthread_mutex_unlock(&registry_lock);
	if (!w)
		return glint_error_set(ENOMEM, "out of memory");
	*out = w;
	return 0;
}

void glint_sim_world_close(struct glint_sim_world *w)
{
	if (!w)
		return;
	pthread_mutex_lock(&registry_lock);
	int last = --w->refs == 0;
	if (last) {
		struct glint_sim_world **p = &registry;
		while (*p != w)
			p = &(*p)->next;
		*p = w->next;
	}
	pthread_mutex_unlock(&registry_lock);
	if (last) {
		pthread_mutex_destroy(&w->lock);
		free(w);
	}
}

void glint_sim_world_get(struct glint_sim_world *w, struct glint_sim_state *st)
{
	pthread_mutex_lock(&w->lock);
	*st = w->st;
	pthread_mutex_unlock(&w->lock);
}

void glint_sim_world_set(struct glint_sim_world *w,
			 const struct glint_sim_state *st)
{
	pthread_mutex_lock(&w->lock);
	w->st = *st;
	pthread_mutex_unlock(&w->lock);
}

void glint_sim_world_reset(struct glint_sim_world *w)
{
	glint_sim_world_set(w, &no_board);
}
