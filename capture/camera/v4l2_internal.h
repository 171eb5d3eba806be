/* SPDX-License-Identifier: MIT */
#ifndef GLINT_CAPTURE_CAMERA_V4L2_INTERNAL_H
#define GLINT_CAPTURE_CAMERA_V4L2_INTERNAL_H

/* Shared by v4l2.c and v4l2_enumerate.c; private to capture/camera/. */

/* ioctl(), resumed after a signal. */
int glint_v4l2_xioctl(int fd, unsigned long req, void *arg);

/* The devices that capture video, one call of found each; their count. */
int glint_v4l2_enumerate(void (*found)(const char *device, void *ctx),
			 void *ctx);

#endif
