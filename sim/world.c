/* SPDX-License-Identifier: MIT */
#include "world.h"

#include <pthread.h>

static pthread_mutex_t world_lock = PTHREAD_MUTEX_INITIALIZER;
static struct glint_sim_world world = { 1, GLINT_SIM_VIEW_PROBE, 0 };

void glint_sim_world_get(struct glint_sim_world *w)
{
	pthread_mutex_lock(&world_lock);
	*w = world;
	pthread_mutex_unlock(&world_lock);
}

void glint_sim_world_set(const struct glint_sim_world *w)
{
	pthread_mutex_lock(&world_lock);
	world = *w;
	pthread_mutex_unlock(&world_lock);
}

void glint_sim_world_reset(void)
{
	struct glint_sim_world w = { 1, GLINT_SIM_VIEW_PROBE, 0 };
	glint_sim_world_set(&w);
}
