/* SPDX-License-Identifier: MIT */
#define _POSIX_C_SOURCE 200809L
/*
 * The V4L2 devices that capture video (/dev/video*, VIDIOC_QUERYCAP), for
 * glint_camera_v4l2_ops.enumerate.
 */
#include "capture/camera/v4l2_internal.h"

#include <fcntl.h>
#include <glob.h>
#include <linux/videodev2.h>
#include <stdint.h>
#include <string.h>
#include <sys/time.h>
#include <unistd.h>

static void found_path(const char *path, void (*found)(const char *, void *),
		       void *ctx, int *n)
{
	found(path, ctx);
	(*n)++;
}

int glint_v4l2_enumerate(void (*found)(const char *device, void *ctx),
			 void *ctx)
{
	glob_t g;
	int n = 0;

	if (glob("/dev/video*", 0, NULL, &g) != 0)
		return 0;
	for (size_t i = 0; i < g.gl_pathc; i++) {
		struct v4l2_capability cap;
		int fd = open(g.gl_pathv[i], O_RDWR | O_NONBLOCK | O_CLOEXEC);
		if (fd < 0)
			continue;
		memset(&cap, 0, sizeof(cap));
		if (glint_v4l2_xioctl(fd, VIDIOC_QUERYCAP, &cap) == 0) {
			uint32_t caps = cap.capabilities & V4L2_CAP_DEVICE_CAPS
						? cap.device_caps
						: cap.capabilities;
			if (caps & V4L2_CAP_VIDEO_CAPTURE)
				found_path(g.gl_pathv[i], found, ctx, &n);
		}
		close(fd);
	}
	globfree(&g);
	return n;
}
