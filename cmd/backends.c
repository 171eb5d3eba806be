/* SPDX-License-Identifier: MIT */
#include "backends.h"

#include "board/board.h"
#include "capture/camera/camera.h"
#include "sim/board_sim.h"
#include "sim/camera_sim.h"

#include <stddef.h>

static const struct glint_camera_ops *const cameras[] = {
	&glint_camera_sim_ops,
#ifdef GLINT_HAVE_V4L2
	&glint_camera_v4l2_ops,
#endif
#ifdef GLINT_HAVE_LIBCAMERA
	&glint_camera_libcamera_ops,
#endif
	NULL,
};

static const struct glint_board_ops *const boards[] = {
#ifdef GLINT_HAVE_GPIOD
	&glint_board_gpiod_ops,
#endif
	&glint_board_sim_ops,
	NULL,
};

void glint_backends_register(void)
{
	glint_camera_backends_set(cameras);
	glint_board_backends_set(boards);
}
