/* SPDX-License-Identifier: MIT */
#include "camera.h"

#include <stddef.h>

const struct glint_camera_ops *const glint_camera_backends[] = {
	&glint_camera_sim_ops,
#ifdef GLINT_HAVE_V4L2
	&glint_camera_v4l2_ops,
#endif
#ifdef GLINT_HAVE_LIBCAMERA
	&glint_camera_libcamera_ops,
#endif
	NULL,
};
