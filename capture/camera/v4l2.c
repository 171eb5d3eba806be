/* SPDX-License-Identifier: MIT */
/*
 * The V4L2 backend, over the kernel's ioctls (no libv4l2: it converts
 * formats behind our back and its raw syscalls would bypass the test
 * suite's fake device).
 *
 * Device string: "/dev/videoN" or "/dev/videoN:key=value,...", keys:
 *   latency=N        the first frame exposed with a new control value is
 *                    the N-th frame to start after the write (default 2:
 *                    sensors latch registers at frame start and apply
 *                    exposure a frame late); 0: the first to end after it
 *   exposure_unit=S  seconds per unit of V4L2_CID_EXPOSURE (default 1e-6;
 *                    V4L2_CID_EXPOSURE_ABSOLUTE is 100 us by definition)
 *   gain_unity=V     gain control value meaning x1 (default: the
 *                    control's default value)
 *   black=DN         black level, when the driver has no
 *                    V4L2_CID_BLACK_LEVEL (default 0)
 *   buffers=N        mmap buffers (2..8, default 4)
 *
 * How an applied exposure is confirmed: V4L2 carries no per-frame
 * metadata, so the backend (1) reads the control back after writing it
 * (the driver's quantised value is what we record), (2) notes the time of
 * the write on CLOCK_MONOTONIC, the clock of buffer timestamps, and
 * (3) labels frames with the new values only from the `latency`-th frame
 * that started after the write (counting frames we dequeue; one the
 * driver dropped makes the label later, never early).  Start of exposure
 * comes from the timestamp (start-of-exposure flag) or from the
 * end-of-frame timestamp minus the longest exposure in flight.  Several
 * writes may be in flight (pipelined brackets); each frame gets the
 * newest one that has landed.  Frames exposed before a request landed
 * carry older values, so glint_camera_capture() drops them.
 * tests/sim/test_v4l2_fake.c checks labels against pixels.
 */
#define _POSIX_C_SOURCE 200809L
#include "capture/camera/camera.h"
#include "capture/camera/v4l2_format.h"
#include "capture/camera/v4l2_internal.h"

#include "core/clock.h"
#include "core/error.h"

#include <errno.h>
#include <fcntl.h>
#include <glob.h>
#include <linux/videodev2.h>
#include <math.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <time.h>
#include <unistd.h>

#define MAX_BUFFERS 8
#define MAX_WRITES  16

struct ctrl {
	uint32_t id;
	const char *name;
	struct v4l2_queryctrl q;
	int present;
};

struct v4l2_cam {
	int fd;
	char path[256];
	struct v4l2_capability cap;
	struct glint_clock clock;
	/* options */
	int latency, nbuf_req;
	double exposure_unit, gain_unity, black;
	int have_black_opt;
	/* formats */
	int nfmt;
	uint32_t fourccs[GLINT_CAMERA_MAX_FORMATS];
	const struct glint_v4l2_format *fmt;
	int width, height;
	size_t stride, sizeimage;
	double period_s;
	/* controls */
	struct ctrl ae, exposure, gain, black_ctrl;
	double exp_unit_s; /* of the exposure control in use */
	int manual;
	/* streaming */
	int streaming, nbuf;
	void *map[MAX_BUFFERS];
	size_t map_len[MAX_BUFFERS];
	/* exposure labelling */
	/* Control writes not yet known to have landed, oldest first, and
	 * the values of the newest one that has. */
	struct write {
		double t;	  /* CLOCK_MONOTONIC of the write */
		double e, g;	  /* values read back */
		long long before; /* newest sequence seen starting before */
		long long first;  /* first sequence seen starting after */
	} writes[MAX_WRITES];
	long long last_seq; /* newest sequence dequeued */
	int nwrites;
	double cur_e, cur_g; /* latest written */
	double base_e, base_g;
};

static double monotonic_now(void)
{
	return glint_clock_monotonic();
}

int glint_v4l2_xioctl(int fd, unsigned long req, void *arg)
{
	int r;
	do
		r = ioctl(fd, req, arg);
	while (r < 0 && errno == EINTR);
	return r;
}

static int ioctl_error(struct v4l2_cam *c, const char *what)
{
	int e = errno ? errno : EIO;
	if (e == ENODEV || e == ENXIO)
		return glint_error_set(ENODEV, "camera %s disappeared (%s: %s)",
				       c->path, what, strerror(e));
	return glint_error_set(e, "camera %s: %s: %s", c->path, what,
			       strerror(e));
}

static int parse_device(const char *dev, struct v4l2_cam *c)
{
	const char *colon;
	size_t n;

	c->latency = 2;
	c->nbuf_req = 4;
	c->exposure_unit = 1e-6;
	if (!dev || !*dev)
		dev = "/dev/video0";
	colon = strchr(dev, ':');
	n = colon ? (size_t)(colon - dev) : strlen(dev);
	if (n >= sizeof(c->path))
		return glint_error_set(ENAMETOOLONG,
				       "v4l2 device '%s': path "
				       "too long",
				       dev);
	memcpy(c->path, dev, n);
	c->path[n] = 0;
	for (const char *p = colon ? colon + 1 : ""; *p;) {
		char key[32];
		double v;
		int k = 0;
		if (sscanf(p, "%31[a-z_]=%lf%n", key, &v, &k) != 2)
			return glint_error_set(EINVAL,
					       "v4l2 device '%s': bad option "
					       "at '%s'",
					       dev, p);
		if (!strcmp(key, "latency") && v >= 0 && v <= 16)
			c->latency = (int)v;
		else if (!strcmp(key, "exposure_unit") && v > 0 && v < 1)
			c->exposure_unit = v;
		else if (!strcmp(key, "gain_unity") && v > 0)
			c->gain_unity = v;
		else if (!strcmp(key, "black") && v >= 0) {
			c->black = v;
			c->have_black_opt = 1;
		} else if (!strcmp(key, "buffers") && v >= 2 &&
			   v <= MAX_BUFFERS)
			c->nbuf_req = (int)v;
		else
			return glint_error_set(
				EINVAL,
				"v4l2 device '%s': option %s=%g: expected "
				"latency (0..16), exposure_unit (s), "
				"gain_unity (>0), black (DN) or buffers "
				"(2..8)",
				dev, key, v);
		p += k;
		if (*p == ',')
			p++;
	}
	return 0;
}

static void query_ctrl(struct v4l2_cam *c, struct ctrl *k, uint32_t id,
		       const char *name)
{
	memset(k, 0, sizeof(*k));
	k->id = id;
	k->name = name;
	k->q.id = id;
	k->present = glint_v4l2_xioctl(c->fd, VIDIOC_QUERYCTRL, &k->q) == 0 &&
		     !(k->q.flags & V4L2_CTRL_FLAG_DISABLED);
}

static int menu_has(struct v4l2_cam *c, uint32_t id, int index)
{
	struct v4l2_querymenu m;
	memset(&m, 0, sizeof(m));
	m.id = id;
	m.index = (uint32_t)index;
	return glint_v4l2_xioctl(c->fd, VIDIOC_QUERYMENU, &m) == 0;
}

static void find_controls(struct v4l2_cam *c)
{
	query_ctrl(c, &c->ae, V4L2_CID_EXPOSURE_AUTO, "exposure_auto");
	query_ctrl(c, &c->exposure, V4L2_CID_EXPOSURE_ABSOLUTE,
		   "exposure_time_absolute");
	c->exp_unit_s = 1e-4;
	if (!c->exposure.present ||
	    (c->exposure.q.flags & V4L2_CTRL_FLAG_READ_ONLY)) {
		query_ctrl(c, &c->exposure, V4L2_CID_EXPOSURE, "exposure");
		c->exp_unit_s = c->exposure_unit;
	}
	query_ctrl(c, &c->gain, V4L2_CID_ANALOGUE_GAIN, "analogue_gain");
	if (!c->gain.present) {
		query_ctrl(c, &c->gain, V4L2_CID_GAIN, "gain");
	}
	query_ctrl(c, &c->black_ctrl, V4L2_CID_BLACK_LEVEL, "black_level");
	/* Manual exposure: a writable exposure control, and either no
	 * auto-exposure menu or one with a manual entry. */
	c->manual = c->exposure.present &&
		    !(c->exposure.q.flags & V4L2_CTRL_FLAG_READ_ONLY) &&
		    (!c->ae.present ||
		     menu_has(c, V4L2_CID_EXPOSURE_AUTO, V4L2_EXPOSURE_MANUAL));
	if (c->gain.present && c->gain_unity <= 0)
		c->gain_unity = c->gain.q.default_value > 0
					? c->gain.q.default_value
					: fmax(c->gain.q.minimum, 1);
}

static int choose_format(struct v4l2_cam *c)
{
	struct v4l2_fmtdesc d;
	const struct glint_v4l2_format *best = NULL;

	c->nfmt = 0;
	/* Every format, however many: vivid lists its raw Bayer ones after
	 * the 64th.  The bound only stops a driver that never says EINVAL. */
	for (uint32_t i = 0; i < 4096; i++) {
		memset(&d, 0, sizeof(d));
		d.index = i;
		d.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
		if (glint_v4l2_xioctl(c->fd, VIDIOC_ENUM_FMT, &d) < 0) {
			if (errno == EINVAL)
				break;
			return ioctl_error(c, "VIDIOC_ENUM_FMT");
		}
		if (c->nfmt < GLINT_CAMERA_MAX_FORMATS)
			c->fourccs[c->nfmt++] = d.pixelformat;
		const struct glint_v4l2_format *f =
			glint_v4l2_format_find(d.pixelformat);
		if (f && (!best || f->rank > best->rank))
			best = f;
	}
	if (!best) {
		char list[160] = "", fc[5];
		for (int i = 0; i < c->nfmt; i++) {
			glint_fourcc_str(c->fourccs[i], fc);
			size_t n = strlen(list);
			snprintf(list + n, sizeof(list) - n, "%s%s",
				 i ? " " : "", fc);
		}
		return glint_error_set(ENOTSUP,
				       "camera %s offers no format glint "
				       "reads (offers: %s; reads raw Bayer "
				       "8-16 bit, GREY, Y16, RGB24, YUYV)",
				       c->path, c->nfmt ? list : "none");
	}
	c->fmt = best;
	return 0;
}

/* The largest frame size offered for the chosen format. */
static void largest_size(struct v4l2_cam *c, uint32_t *w, uint32_t *h)
{
	struct v4l2_frmsizeenum s;
	for (uint32_t i = 0; i < 64; i++) {
		memset(&s, 0, sizeof(s));
		s.index = i;
		s.pixel_format = c->fmt->fourcc;
		if (glint_v4l2_xioctl(c->fd, VIDIOC_ENUM_FRAMESIZES, &s) < 0)
			break;
		if (s.type == V4L2_FRMSIZE_TYPE_DISCRETE) {
			if ((uint64_t)s.discrete.width * s.discrete.height >
			    (uint64_t)*w * *h) {
				*w = s.discrete.width;
				*h = s.discrete.height;
			}
		} else {
			*w = s.stepwise.max_width;
			*h = s.stepwise.max_height;
			break;
		}
	}
}

static int set_format(struct v4l2_cam *c)
{
	struct v4l2_format f;
	uint32_t w = 0, h = 0;
	char want[5], got[5];

	memset(&f, 0, sizeof(f));
	f.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
	if (glint_v4l2_xioctl(c->fd, VIDIOC_G_FMT, &f) < 0)
		return ioctl_error(c, "VIDIOC_G_FMT");
	w = f.fmt.pix.width;
	h = f.fmt.pix.height;
	largest_size(c, &w, &h);
	f.fmt.pix.width = w;
	f.fmt.pix.height = h;
	f.fmt.pix.pixelformat = c->fmt->fourcc;
	f.fmt.pix.field = V4L2_FIELD_NONE;
	f.fmt.pix.bytesperline = 0;
	if (glint_v4l2_xioctl(c->fd, VIDIOC_S_FMT, &f) < 0)
		return ioctl_error(c, "VIDIOC_S_FMT");
	glint_fourcc_str(c->fmt->fourcc, want);
	glint_fourcc_str(f.fmt.pix.pixelformat, got);
	if (f.fmt.pix.pixelformat != c->fmt->fourcc)
		return glint_error_set(EIO,
				       "camera %s: asked for format %s, "
				       "driver set %s",
				       c->path, want, got);
	c->width = (int)f.fmt.pix.width;
	c->height = (int)f.fmt.pix.height;
	c->stride = f.fmt.pix.bytesperline
			    ? f.fmt.pix.bytesperline
			    : glint_v4l2_row_bytes(c->fmt, c->width);
	c->sizeimage = f.fmt.pix.sizeimage;
	if (c->width < 2 || c->height < 2 ||
	    c->stride < glint_v4l2_row_bytes(c->fmt, c->width))
		return glint_error_set(EIO,
				       "camera %s: driver set %dx%d with %zu "
				       "bytes per line for %s",
				       c->path, c->width, c->height, c->stride,
				       want);
	/* Frame period: the driver's time per frame, 1/30 s if unknown. */
	struct v4l2_streamparm p;
	memset(&p, 0, sizeof(p));
	p.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
	c->period_s = 1.0 / 30;
	if (glint_v4l2_xioctl(c->fd, VIDIOC_G_PARM, &p) == 0 &&
	    p.parm.capture.timeperframe.denominator > 0 &&
	    p.parm.capture.timeperframe.numerator > 0)
		c->period_s = (double)p.parm.capture.timeperframe.numerator /
			      p.parm.capture.timeperframe.denominator;
	return 0;
}

static int v4l2_open(const char *device, const struct glint_clock *clock,
		     void **priv)
{
	struct v4l2_cam *c = calloc(1, sizeof(*c));
	int ret;

	*priv = NULL;
	if (!c)
		return glint_error_set(ENOMEM, "out of memory");
	c->fd = -1;
	c->last_seq = -1;
	c->clock = *clock;
	ret = parse_device(device, c);
	if (ret < 0)
		goto err;
	c->fd = open(c->path, O_RDWR | O_NONBLOCK | O_CLOEXEC);
	if (c->fd < 0) {
		int e = errno;
		ret = glint_error_set(e, "camera %s: %s%s", c->path,
				      strerror(e),
				      e == EBUSY    ? " (another program is "
						      "using it)"
				      : e == EACCES ? " (add yourself to "
						      "group video)"
						    : "");
		goto err;
	}
	memset(&c->cap, 0, sizeof(c->cap));
	if (glint_v4l2_xioctl(c->fd, VIDIOC_QUERYCAP, &c->cap) < 0) {
		ret = errno == ENOTTY
			      ? glint_error_set(ENOTTY,
						"%s is not a V4L2 device",
						c->path)
			      : ioctl_error(c, "VIDIOC_QUERYCAP");
		goto err;
	}
	uint32_t caps = c->cap.capabilities & V4L2_CAP_DEVICE_CAPS
				? c->cap.device_caps
				: c->cap.capabilities;
	if (!(caps & V4L2_CAP_VIDEO_CAPTURE) || !(caps & V4L2_CAP_STREAMING)) {
		ret = glint_error_set(ENOTSUP,
				      "camera %s (%s): not a streaming video "
				      "capture device (capabilities 0x%08x)",
				      c->path, (const char *)c->cap.card, caps);
		goto err;
	}
	ret = choose_format(c);
	if (ret < 0)
		goto err;
	find_controls(c);
	*priv = c;
	return 0;
err:
	if (c->fd >= 0)
		close(c->fd);
	free(c);
	return ret;
}

static void stop_streaming(struct v4l2_cam *c)
{
	if (c->streaming) {
		int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
		glint_v4l2_xioctl(c->fd, VIDIOC_STREAMOFF, &type);
		c->streaming = 0;
	}
	for (int i = 0; i < c->nbuf; i++)
		if (c->map[i] && c->map[i] != MAP_FAILED)
			munmap(c->map[i], c->map_len[i]);
	if (c->nbuf) {
		struct v4l2_requestbuffers rb;
		memset(&rb, 0, sizeof(rb));
		rb.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
		rb.memory = V4L2_MEMORY_MMAP;
		glint_v4l2_xioctl(c->fd, VIDIOC_REQBUFS, &rb);
	}
	c->nbuf = 0;
}

static void v4l2_close(void *priv)
{
	struct v4l2_cam *c = priv;
	if (!c)
		return;
	stop_streaming(c);
	close(c->fd);
	free(c);
}

static int v4l2_describe(void *priv, struct glint_camera_info *in)
{
	struct v4l2_cam *c = priv;

	memset(in, 0, sizeof(*in));
	snprintf(in->backend, sizeof(in->backend), "v4l2");
	snprintf(in->name, sizeof(in->name), "%s", (const char *)c->cap.card);
	glint_text(in->detail, sizeof(in->detail), "%s, driver %s, %s", c->path,
		   (const char *)c->cap.driver, (const char *)c->cap.bus_info);
	in->width = c->width;
	in->height = c->height;
	for (int i = 0; i < c->nfmt && i < GLINT_CAMERA_MAX_FORMATS; i++) {
		const struct glint_v4l2_format *f =
			glint_v4l2_format_find(c->fourccs[i]);
		char fc[5];
		glint_fourcc_str(c->fourccs[i], fc);
		snprintf(in->formats[in->nformats++], sizeof(in->formats[0]),
			 "%s", f ? f->name : fc);
	}
	in->bit_depth = c->fmt->bits;
	in->manual_exposure = c->manual;
	if (c->exposure.present) {
		in->exposure_min_s =
			fmax(c->exposure.q.minimum, 1) * c->exp_unit_s;
		in->exposure_max_s = c->exposure.q.maximum * c->exp_unit_s;
		in->exposure_step_s =
			fmax(c->exposure.q.step, 1) * c->exp_unit_s;
		snprintf(in->exposure_control, sizeof(in->exposure_control),
			 "%s (%g s units)", c->exposure.name, c->exp_unit_s);
	} else {
		snprintf(in->exposure_control, sizeof(in->exposure_control),
			 "none");
	}
	if (c->gain.present) {
		in->gain_min = c->gain.q.minimum / c->gain_unity;
		in->gain_max = c->gain.q.maximum / c->gain_unity;
		in->gain_step = fmax(c->gain.q.step, 1) / c->gain_unity;
		snprintf(in->gain_control, sizeof(in->gain_control),
			 "%s (x1 = %g)", c->gain.name, c->gain_unity);
	} else {
		in->gain_min = in->gain_max = 1;
		snprintf(in->gain_control, sizeof(in->gain_control), "none");
	}
	in->frame_period_min_s = c->period_s;
	in->latency_frames = c->latency;
	return 0;
}

static int start_streaming(struct v4l2_cam *c)
{
	struct v4l2_requestbuffers rb;
	int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;

	memset(&rb, 0, sizeof(rb));
	rb.count = (uint32_t)c->nbuf_req;
	rb.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
	rb.memory = V4L2_MEMORY_MMAP;
	if (glint_v4l2_xioctl(c->fd, VIDIOC_REQBUFS, &rb) < 0)
		return ioctl_error(c, "VIDIOC_REQBUFS");
	if (rb.count < 2)
		return glint_error_set(ENOMEM,
				       "camera %s: driver granted %u buffers, "
				       "need 2",
				       c->path, rb.count);
	c->nbuf = rb.count > MAX_BUFFERS ? MAX_BUFFERS : (int)rb.count;
	for (int i = 0; i < c->nbuf; i++) {
		struct v4l2_buffer b;
		memset(&b, 0, sizeof(b));
		b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
		b.memory = V4L2_MEMORY_MMAP;
		b.index = (uint32_t)i;
		if (glint_v4l2_xioctl(c->fd, VIDIOC_QUERYBUF, &b) < 0)
			return ioctl_error(c, "VIDIOC_QUERYBUF");
		c->map_len[i] = b.length;
		c->map[i] = mmap(NULL, b.length, PROT_READ | PROT_WRITE,
				 MAP_SHARED, c->fd, b.m.offset);
		if (c->map[i] == MAP_FAILED) {
			c->map[i] = NULL;
			return ioctl_error(c, "mmap");
		}
		if (glint_v4l2_xioctl(c->fd, VIDIOC_QBUF, &b) < 0)
			return ioctl_error(c, "VIDIOC_QBUF");
	}
	if (glint_v4l2_xioctl(c->fd, VIDIOC_STREAMON, &type) < 0)
		return ioctl_error(c, "VIDIOC_STREAMON");
	c->streaming = 1;
	return 0;
}

static int v4l2_configure(void *priv)
{
	struct v4l2_cam *c = priv;
	int ret = set_format(c);
	if (ret < 0)
		return ret;
	if (c->have_black_opt || !c->black_ctrl.present) {
		/* the option, or 0 */
	} else {
		struct v4l2_control k = { V4L2_CID_BLACK_LEVEL, 0 };
		if (glint_v4l2_xioctl(c->fd, VIDIOC_G_CTRL, &k) == 0)
			c->black = k.value;
	}
	return 0;
}

static int write_ctrl(struct v4l2_cam *c, const struct ctrl *k, int32_t v,
		      int32_t *applied)
{
	struct v4l2_control w = { k->id, v };
	if (glint_v4l2_xioctl(c->fd, VIDIOC_S_CTRL, &w) < 0) {
		char what[96];
		snprintf(what, sizeof(what), "setting %s to %d", k->name,
			 (int)v);
		return ioctl_error(c, what);
	}
	w.value = 0;
	if (glint_v4l2_xioctl(c->fd, VIDIOC_G_CTRL, &w) < 0) {
		char what[96];
		snprintf(what, sizeof(what), "reading back %s", k->name);
		return ioctl_error(c, what);
	}
	*applied = w.value;
	return 0;
}

static int clamp_ctrl(const struct ctrl *k, double v)
{
	double step = fmax(k->q.step, 1);
	double q = k->q.minimum + step * floor((v - k->q.minimum) / step + 0.5);
	return (int)fmin(fmax(q, k->q.minimum), k->q.maximum);
}

static int v4l2_set_exposure(void *priv, double *exposure_s, double *gain)
{
	struct v4l2_cam *c = priv;
	int32_t got;
	int ret;

	if (!c->manual)
		return glint_error_set(
			ENOTSUP, "camera %s: no manual exposure (%s)", c->path,
			c->exposure.present ? "V4L2_CID_EXPOSURE_AUTO has "
					      "no manual mode"
					    : "no V4L2_CID_EXPOSURE_ABSOLUTE "
					      "or V4L2_CID_EXPOSURE");
	if (!c->streaming) {
		ret = start_streaming(c);
		if (ret < 0)
			return ret;
	}
	if (c->ae.present) {
		ret = write_ctrl(c, &c->ae, V4L2_EXPOSURE_MANUAL, &got);
		if (ret < 0)
			return ret;
		if (got != V4L2_EXPOSURE_MANUAL)
			return glint_error_set(EIO,
					       "camera %s: exposure_auto reads "
					       "back %d after setting manual",
					       c->path, (int)got);
	}
	ret = write_ctrl(c, &c->exposure,
			 clamp_ctrl(&c->exposure, *exposure_s / c->exp_unit_s),
			 &got);
	if (ret < 0)
		return ret;
	c->cur_e = got * c->exp_unit_s;
	c->cur_g = 1;
	if (c->gain.present) {
		ret = write_ctrl(c, &c->gain,
				 clamp_ctrl(&c->gain, *gain * c->gain_unity),
				 &got);
		if (ret < 0)
			return ret;
		c->cur_g = got / c->gain_unity;
	}
	if (c->nwrites == MAX_WRITES) { /* the oldest must have landed */
		c->base_e = c->writes[0].e;
		c->base_g = c->writes[0].g;
		memmove(c->writes, c->writes + 1,
			(MAX_WRITES - 1) * sizeof(c->writes[0]));
		c->nwrites--;
	}
	c->writes[c->nwrites++] = (struct write){ monotonic_now(), c->cur_e,
						  c->cur_g, c->last_seq, -1 };
	*exposure_s = c->cur_e;
	*gain = c->cur_g;
	return 0;
}

/* The values a frame was exposed with: those of the newest write that
 * has landed by it (the `latency`-th frame to start after the write; with
 * latency 0 the first to end after it).  When the driver dropped frames
 * around a write, the frames that may or may not have the new values get
 * exposure 0 (unknown), so no capture accepts them. */
static void label_frame(struct v4l2_cam *c, long long seq, int soe, double ts,
			double *e, double *g)
{
	double emin = c->base_e, emax = c->base_e;
	for (int i = 0; i < c->nwrites; i++) {
		emin = fmin(emin, c->writes[i].e);
		emax = fmax(emax, c->writes[i].e);
	}
	/* Start and end of exposure, conservatively when only one end is
	 * stamped. */
	double start = soe ? ts : ts - emax;
	double end = soe ? ts + emin : ts;
	int landed = -1, unsure = 0;
	c->last_seq = seq;
	for (int i = 0; i < c->nwrites; i++) {
		struct write *w = &c->writes[i];
		if (c->latency == 0) {
			if (end >= w->t)
				landed = i;
			continue;
		}
		if (w->first < 0 && start < w->t)
			w->before = seq;
		else if (w->first < 0)
			w->first = seq;
		if (w->first < 0)
			continue;
		if (seq >= w->first + c->latency - 1)
			landed = i;
		else if (w->first > w->before + 1)
			unsure = 1; /* dropped frames hide where it landed */
	}
	if (landed >= 0) {
		c->base_e = c->writes[landed].e;
		c->base_g = c->writes[landed].g;
		memmove(c->writes, c->writes + landed + 1,
			(size_t)(c->nwrites - landed - 1) *
				sizeof(c->writes[0]));
		c->nwrites -= landed + 1;
	}
	*e = unsure ? 0 : c->base_e;
	*g = unsure ? 0 : c->base_g;
}

static int v4l2_grab(void *priv, struct glint_frame *f)
{
	struct v4l2_cam *c = priv;
	struct v4l2_buffer b;
	double timeout = fmax(2.0, 3 * fmax(c->cur_e, c->period_s) + 1);
	double t_end_wait = c->clock.now(c->clock.ctx) + timeout;
	int ret;

	memset(f, 0, sizeof(*f));
	if (!c->streaming) {
		ret = start_streaming(c);
		if (ret < 0)
			return ret;
	}
	for (;;) {
		struct pollfd p = { c->fd, POLLIN, 0 };
		double left = t_end_wait - c->clock.now(c->clock.ctx);
		if (left <= 0)
			return glint_error_set(ETIMEDOUT,
					       "camera %s: no frame within "
					       "%.1f s (exposure %g s)",
					       c->path, timeout, c->cur_e);
		int r = poll(&p, 1, (int)ceil(left * 1000));
		if (r < 0) {
			if (errno == EINTR)
				continue;
			return ioctl_error(c, "poll");
		}
		if (r == 0)
			continue;
		if (p.revents & (POLLERR | POLLHUP | POLLNVAL)) {
			errno = ENODEV;
			return ioctl_error(c, "poll");
		}
		memset(&b, 0, sizeof(b));
		b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
		b.memory = V4L2_MEMORY_MMAP;
		if (glint_v4l2_xioctl(c->fd, VIDIOC_DQBUF, &b) < 0) {
			if (errno == EAGAIN)
				continue;
			return ioctl_error(c, "VIDIOC_DQBUF");
		}
		if (!(b.flags & V4L2_BUF_FLAG_ERROR) &&
		    b.index < (uint32_t)c->nbuf)
			break;
		/* A corrupted frame: give the buffer back, wait for more. */
		if (glint_v4l2_xioctl(c->fd, VIDIOC_QBUF, &b) < 0)
			return ioctl_error(c, "VIDIOC_QBUF");
	}
	size_t n = (size_t)c->width * c->height * c->fmt->channels;
	f->data = malloc(n * sizeof(uint16_t));
	if (!f->data)
		ret = glint_error_set(ENOMEM, "camera %s: out of memory",
				      c->path);
	else
		ret = glint_v4l2_convert(
			c->fmt, c->map[b.index],
			b.bytesused ? b.bytesused : c->map_len[b.index],
			c->stride, c->width, c->height, f->data);
	if (ret < 0)
		glint_error_prefix(ret, "camera %s, frame %u", c->path,
				   b.sequence);
	/* What the frame was, kept before the buffer goes back: VIDIOC_QBUF
	 * writes the queued buffer's state into b (vb2 zeroes its sequence
	 * number; vivid showed every frame as number 0). */
	const struct v4l2_buffer got = b;
	if (glint_v4l2_xioctl(c->fd, VIDIOC_QBUF, &b) < 0 && ret == 0)
		ret = ioctl_error(c, "VIDIOC_QBUF");
	if (ret < 0) {
		glint_frame_release(f);
		return ret;
	}
	glint_v4l2_frame_describe(c->fmt, c->width, c->height, f);
	/* Buffer timestamps are CLOCK_MONOTONIC: start of exposure or end
	 * of frame, as the flags say. */
	double ts = (double)got.timestamp.tv_sec + 1e-6 * got.timestamp.tv_usec;
	int soe = (got.flags & V4L2_BUF_FLAG_TSTAMP_SRC_MASK) ==
		  V4L2_BUF_FLAG_TSTAMP_SRC_SOE;
	label_frame(c, got.sequence, soe, ts, &f->exposure_s, &f->gain);
	f->black_level = c->black;
	f->sequence = got.sequence;
	f->t_start = soe ? ts : ts - f->exposure_s;
	f->t_end = soe ? ts + f->exposure_s : ts;
	return 0;
}

const struct glint_camera_ops glint_camera_v4l2_ops = {
	.name = "v4l2",
	.open = v4l2_open,
	.close = v4l2_close,
	.describe = v4l2_describe,
	.configure = v4l2_configure,
	.set_exposure = v4l2_set_exposure,
	.grab = v4l2_grab,
	.enumerate = glint_v4l2_enumerate,
};
