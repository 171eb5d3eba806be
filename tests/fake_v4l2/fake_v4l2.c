/* SPDX-License-Identifier: MIT */
/*
 * A fake V4L2 camera for tests: an LD_PRELOAD interposer of open, close,
 * ioctl, mmap and poll (and their *64 names) that serves the simulated
 * sensor (sim/camera_sim.c) through the kernel's real ioctl protocol, so
 * capture/camera/v4l2.c runs unchanged, and injects the faults real cameras
 * have.
 *
 * Configured by the environment, read at each open:
 *   FAKE_V4L2="key=value,..."  keys:
 *     path=/dev/video0      the device node it answers for (default)
 *     formats=A:B:...       V4L2 format names offered, in order (default
 *                           SRGGB8:SRGGB10P:SRGGB12:YUYV)
 *     width=64,height=48    frame size
 *     latency=1             frames starting after a control write that
 *                           still use the old values (registers latch at
 *                           frame start)
 *     timescale=0.01        real seconds per sensor second
 *     noise=0|1, seed=N     sensor noise
 *     manual=0              exposure_auto offers no manual mode
 *     busy=1                open fails with EBUSY
 *     refuse=exposure|gain|auto   VIDIOC_S_CTRL on it fails with EACCES
 *   faults, counted in frames the client has dequeued (VIDIOC_DQBUF):
 *     enodev_after=N        unplugged after N: ENODEV, POLLERR
 *     eio_at=N              the N-th VIDIOC_DQBUF (from 0) fails with EIO
 *     stall_after=N         no frame after N
 *     short_from=N          from the N-th on, frames arrive truncated
 *                           (bytesused / 2)
 *
 * Simplification: a frame starts only when a buffer is queued for it (a
 * real sensor keeps running and the driver drops the frame), so that the
 * host never renders frames nobody reads.
 *
 * The fd it returns is a memfd holding the buffers, so mmap of it is
 * real shared memory.  A poll() that names the fake fd among others only
 * waits for the fake one.
 */
/* Interpose the plain and the *64 names both: see them undecorated. */
#undef _FILE_OFFSET_BITS
#define _GNU_SOURCE
#include "capture/camera/camera.h"
#include "capture/camera/v4l2_format.h"
#include "sim/camera_sim.h"

#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
#include <linux/videodev2.h>
#include <math.h>
#include <poll.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <time.h>
#include <unistd.h>

#define NBUF_MAX 8
#define NFMT_MAX 16

enum { B_CLIENT, B_QUEUED, B_DONE };

struct fake {
	int fd;
	char path[128];
	uint32_t fmts[NFMT_MAX];
	int nfmt;
	uint32_t fourcc;
	int width, height, latency, noise, manual, busy;
	double timescale;
	unsigned long seed;
	char refuse[16];
	long enodev_after, eio_at, stall_after, short_from;
	/* controls */
	int ae, exposure, gain;
	/* buffers */
	int nbuf;
	size_t bufsize, stride, sizeimage;
	uint8_t *mem;
	int state[NBUF_MAX];
	struct v4l2_buffer meta[NBUF_MAX];
	int done[NBUF_MAX], ndone;
	/* the sensor */
	int streaming, unplugged;
	void *sim;
	struct glint_fake_clock fc;
	struct glint_clock clock;
	double t0_real;
	struct glint_frame next; /* the frame being exposed (data != NULL) */
	double next_start;	 /* sensor time the next frame starts */
	long produced;		 /* frames the sensor completed */
	long dequeued;		 /* frames the client dequeued */
	int paused;		 /* waiting for a buffer to start a frame */
};

static pthread_mutex_t lock = PTHREAD_MUTEX_INITIALIZER;
static struct fake *dev;

static int (*real_open)(const char *, int, ...);
static int (*real_open64)(const char *, int, ...);
static int (*real_close)(int);
static int (*real_ioctl)(int, unsigned long, ...);
static void *(*real_mmap)(void *, size_t, int, int, int, off_t);
static void *(*real_mmap64)(void *, size_t, int, int, int, off_t);
static int (*real_poll)(struct pollfd *, nfds_t, int);

static void resolve(void)
{
	if (real_open)
		return;
	real_open = (int (*)(const char *, int, ...))dlsym(RTLD_NEXT, "open");
	real_open64 =
		(int (*)(const char *, int, ...))dlsym(RTLD_NEXT, "open64");
	real_close = (int (*)(int))dlsym(RTLD_NEXT, "close");
	real_ioctl =
		(int (*)(int, unsigned long, ...))dlsym(RTLD_NEXT, "ioctl");
	real_mmap = (void *(*)(void *, size_t, int, int, int, off_t))dlsym(
		RTLD_NEXT, "mmap");
	real_mmap64 = (void *(*)(void *, size_t, int, int, int, off_t))dlsym(
		RTLD_NEXT, "mmap64");
	real_poll =
		(int (*)(struct pollfd *, nfds_t, int))dlsym(RTLD_NEXT, "poll");
}

static double now_real(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void configure_from_env(struct fake *f)
{
	const char *env = getenv("FAKE_V4L2");
	char buf[512];

	snprintf(f->path, sizeof(f->path), "/dev/video0");
	f->width = 64;
	f->height = 48;
	f->latency = 1;
	f->timescale = 0.01;
	f->noise = 1;
	f->seed = 1;
	f->manual = 1;
	f->enodev_after = f->eio_at = f->stall_after = f->short_from = -1;
	snprintf(buf, sizeof(buf), "%s",
		 "formats=SRGGB8:SRGGB10P:SRGGB12:YUYV");
	if (env) {
		size_t n = strlen(buf);
		snprintf(buf + n, sizeof(buf) - n, ",%s", env);
	}
	for (char *save = NULL, *kv = strtok_r(buf, ",", &save); kv;
	     kv = strtok_r(NULL, ",", &save)) {
		char *eq = strchr(kv, '=');
		if (!eq)
			continue;
		*eq = 0;
		const char *v = eq + 1;
		if (!strcmp(kv, "path"))
			snprintf(f->path, sizeof(f->path), "%s", v);
		else if (!strcmp(kv, "formats")) {
			char list[256];
			f->nfmt = 0;
			snprintf(list, sizeof(list), "%s", v);
			for (char *s2 = NULL, *nm = strtok_r(list, ":", &s2);
			     nm && f->nfmt < NFMT_MAX;
			     nm = strtok_r(NULL, ":", &s2)) {
				const struct glint_v4l2_format *g =
					glint_v4l2_format_by_name(nm);
				if (g)
					f->fmts[f->nfmt++] = g->fourcc;
				else if (!strcmp(nm, "MJPG"))
					f->fmts[f->nfmt++] = V4L2_PIX_FMT_MJPEG;
			}
		} else if (!strcmp(kv, "width"))
			f->width = atoi(v);
		else if (!strcmp(kv, "height"))
			f->height = atoi(v);
		else if (!strcmp(kv, "latency"))
			f->latency = atoi(v);
		else if (!strcmp(kv, "timescale"))
			f->timescale = atof(v);
		else if (!strcmp(kv, "noise"))
			f->noise = atoi(v);
		else if (!strcmp(kv, "seed"))
			f->seed = strtoul(v, NULL, 10);
		else if (!strcmp(kv, "manual"))
			f->manual = atoi(v);
		else if (!strcmp(kv, "busy"))
			f->busy = atoi(v);
		else if (!strcmp(kv, "refuse"))
			snprintf(f->refuse, sizeof(f->refuse), "%s", v);
		else if (!strcmp(kv, "enodev_after"))
			f->enodev_after = atol(v);
		else if (!strcmp(kv, "eio_at"))
			f->eio_at = atol(v);
		else if (!strcmp(kv, "stall_after"))
			f->stall_after = atol(v);
		else if (!strcmp(kv, "short_from"))
			f->short_from = atol(v);
	}
	f->fourcc = f->nfmt ? f->fmts[0] : 0;
	f->ae = V4L2_EXPOSURE_APERTURE_PRIORITY;
	f->exposure = 100; /* 10 ms in 100 us units */
	f->gain = 16;	   /* x1 */
}

static const struct glint_v4l2_format *cur_fmt(const struct fake *f)
{
	return glint_v4l2_format_find(f->fourcc);
}

/* Written independently of capture/camera/v4l2_format.c's reader. */
static size_t row_bytes(uint32_t fourcc, int w)
{
	const struct glint_v4l2_format *g = glint_v4l2_format_find(fourcc);
	switch (g ? g->packing : GLINT_PACK_8) {
	case GLINT_PACK_10P:
		return (size_t)(w + 3) / 4 * 5;
	case GLINT_PACK_12P:
		return (size_t)(w + 1) / 2 * 3;
	case GLINT_PACK_16:
	case GLINT_PACK_YUYV:
		return (size_t)w * 2;
	case GLINT_PACK_RGB24:
		return (size_t)w * 3;
	default:
		return (size_t)w;
	}
}

static void set_geometry(struct fake *f)
{
	size_t row = row_bytes(f->fourcc, f->width);
	const struct glint_v4l2_format *g = cur_fmt(f);
	/* 16-bit rows padded to 64 bytes, as many drivers do. */
	f->stride =
		g && g->packing == GLINT_PACK_16 ? (row + 63) / 64 * 64 : row;
	f->sizeimage = f->stride * (size_t)f->height;
}

/* The sensor's 12-bit value shifted to the format's depth. */
static unsigned to_bits(unsigned v12, int bits)
{
	return bits >= 12 ? v12 << (bits - 12) : v12 >> (12 - bits);
}

static double srgb(double c)
{
	c = c < 0 ? 0 : c > 1 ? 1 : c;
	return c <= 0.0031308 ? 12.92 * c : 1.055 * pow(c, 1 / 2.4) - 0.055;
}

/* R'G'B' (0..1) of pixel (x, y) from its Bayer quad. */
static void quad_rgb(const struct glint_frame *fr, int x, int y, double *rgb)
{
	int x0 = x & ~1, y0 = y & ~1, w = fr->width;
	const uint16_t *d = fr->data;
	double r = d[(size_t)y0 * w + x0],
	       g = 0.5 *
		   (d[(size_t)y0 * w + x0 + 1] + d[(size_t)(y0 + 1) * w + x0]),
	       b = d[(size_t)(y0 + 1) * w + x0 + 1];
	double k = 1.0 / (4095 - fr->black_level);
	rgb[0] = srgb((r - fr->black_level) * k);
	rgb[1] = srgb((g - fr->black_level) * k);
	rgb[2] = srgb((b - fr->black_level) * k);
}

static void pack_frame(const struct fake *f, const struct glint_frame *fr,
		       uint8_t *out)
{
	const struct glint_v4l2_format *g = cur_fmt(f);
	int w = f->width;

	for (int y = 0; y < f->height; y++) {
		uint8_t *o = out + (size_t)y * f->stride;
		const uint16_t *s = fr->data + (size_t)y * w;
		switch (g->packing) {
		case GLINT_PACK_8:
			for (int x = 0; x < w; x++)
				o[x] = (uint8_t)to_bits(s[x], 8);
			break;
		case GLINT_PACK_16:
			for (int x = 0; x < w; x++) {
				unsigned v = to_bits(s[x], g->bits);
				o[2 * x] = (uint8_t)(v & 0xff);
				o[2 * x + 1] = (uint8_t)(v >> 8);
			}
			break;
		case GLINT_PACK_10P:
			memset(o, 0, row_bytes(f->fourcc, w));
			for (int x = 0; x < w; x++) {
				unsigned v = to_bits(s[x], 10);
				o[x / 4 * 5 + x % 4] = (uint8_t)(v >> 2);
				o[x / 4 * 5 + 4] |=
					(uint8_t)((v & 3) << (2 * (x % 4)));
			}
			break;
		case GLINT_PACK_12P:
			memset(o, 0, row_bytes(f->fourcc, w));
			for (int x = 0; x < w; x++) {
				unsigned v = s[x];
				o[x / 2 * 3 + x % 2] = (uint8_t)(v >> 4);
				o[x / 2 * 3 + 2] |=
					(uint8_t)((v & 15) << (4 * (x % 2)));
			}
			break;
		case GLINT_PACK_RGB24:
			for (int x = 0; x < w; x++) {
				double c[3];
				quad_rgb(fr, x, y, c);
				for (int k = 0; k < 3; k++)
					o[3 * x + k] =
						(uint8_t)lround(255 * c[k]);
			}
			break;
		case GLINT_PACK_YUYV:
			for (int x = 0; x + 1 < w; x += 2) {
				double a[3], b[3], m[3];
				quad_rgb(fr, x, y, a);
				quad_rgb(fr, x + 1, y, b);
				for (int k = 0; k < 3; k++)
					m[k] = 0.5 * (a[k] + b[k]);
				o[2 * x] = (uint8_t)lround(16 + 65.481 * a[0] +
							   128.553 * a[1] +
							   24.966 * a[2]);
				o[2 * x + 2] = (uint8_t)lround(
					16 + 65.481 * b[0] + 128.553 * b[1] +
					24.966 * b[2]);
				o[2 * x + 1] = (uint8_t)lround(
					128 - 37.797 * m[0] - 74.203 * m[1] +
					112 * m[2]);
				o[2 * x + 3] = (uint8_t)lround(
					128 + 112 * m[0] - 93.786 * m[1] -
					18.214 * m[2]);
			}
			break;
		}
	}
}

static void set_sim_exposure(struct fake *f)
{
	double e = f->exposure * 1e-4, g = f->gain / 16.0;
	glint_camera_sim_ops.set_exposure(f->sim, &e, &g);
}

static int sensor_start(struct fake *f)
{
	char d[160];
	f->fc.t = 0;
	f->clock = glint_clock_fake(&f->fc);
	snprintf(d, sizeof(d),
		 "sim:width=%d,height=%d,latency=%d,noise=%d,"
		 "seed=%lu",
		 f->width, f->height, f->latency, f->noise, f->seed);
	if (glint_camera_sim_ops.open(d, &f->clock, &f->sim) < 0)
		return -EINVAL;
	set_sim_exposure(f);
	f->t0_real = now_real();
	f->produced = 0;
	f->dequeued = 0;
	f->next_start = 0;
	return 0;
}

static void sensor_stop(struct fake *f)
{
	if (f->sim) {
		glint_frame_release(&f->next);
		glint_camera_sim_ops.close(f->sim);
		f->sim = NULL;
	}
}

/* Complete every frame whose exposure ended by now (sensor time). */
static void catch_up(struct fake *f)
{
	if (!f->streaming || f->unplugged)
		return;
	double t = (now_real() - f->t0_real) / f->timescale;
	int rendered = 0;
	for (;;) {
		/* Registers latch when a frame starts: render it then. */
		if (!f->next.data) {
			if (f->next_start > t)
				return;
			/* Rendering frames nobody has a buffer for costs the
			 * host more than the sensor: the sensor waits for a
			 * buffer (QBUF restarts it) instead of dropping. */
			int queued = 0;
			for (int i = 0; i < f->nbuf; i++)
				queued |= f->state[i] == B_QUEUED;
			if (!queued) {
				f->paused = 1;
				return;
			}
			if (f->stall_after >= 0 &&
			    f->dequeued >= f->stall_after)
				return;
			/* A host too slow to render at the time scale: the
			 * sensor's clock slips instead of falling ever
			 * further behind. */
			if (++rendered > 2 * NBUF_MAX) {
				f->t0_real = now_real() -
					     f->next_start * f->timescale;
				t = f->next_start;
			}
			f->fc.t = f->next_start;
			if (glint_camera_sim_ops.grab(f->sim, &f->next) < 0)
				return;
			/* Frame period: max(exposure, 1/30 s), as the sim. */
			f->next_start = f->next.t_start +
					fmax(f->next.exposure_s, 1.0 / 30);
		}
		if (f->next.t_end > t)
			return;
		if (f->stall_after >= 0 && f->dequeued >= f->stall_after)
			return;
		if (f->enodev_after >= 0 && f->dequeued >= f->enodev_after) {
			f->unplugged = 1;
			return;
		}
		int b = -1;
		for (int i = 0; i < f->nbuf; i++)
			if (f->state[i] == B_QUEUED) {
				b = i;
				break;
			}
		if (b >= 0) { /* else the frame is lost, as in a driver */
			struct v4l2_buffer *m = &f->meta[b];
			pack_frame(f, &f->next,
				   f->mem + (size_t)b * f->bufsize);
			m->bytesused = (uint32_t)f->sizeimage;

			m->sequence = (uint32_t)f->produced;
			double ts = f->t0_real + f->next.t_start * f->timescale;
			m->timestamp.tv_sec = (time_t)ts;
			m->timestamp.tv_usec =
				(long)((ts - (double)(time_t)ts) * 1e6);
			m->flags = V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC |
				   V4L2_BUF_FLAG_TSTAMP_SRC_SOE |
				   V4L2_BUF_FLAG_DONE;
			f->state[b] = B_DONE;
			f->done[f->ndone++] = b;
		}
		f->produced++;
		glint_frame_release(&f->next);
	}
}

/* Real seconds until the next frame completes (a large number if none
 * will). */
static double until_next(const struct fake *f)
{
	if (!f->streaming || f->unplugged ||
	    (f->stall_after >= 0 && f->dequeued >= f->stall_after))
		return 1e9;
	double t = f->next.data ? f->next.t_end : f->next_start;
	return f->t0_real + t * f->timescale - now_real();
}

static int fail(int e)
{
	errno = e;
	return -1;
}

static int queryctrl(struct fake *f, struct v4l2_queryctrl *q)
{
	uint32_t id = q->id;
	memset(q, 0, sizeof(*q));
	q->id = id;
	q->step = 1;
	switch (id) {
	case V4L2_CID_EXPOSURE_AUTO:
		q->type = V4L2_CTRL_TYPE_MENU;
		snprintf((char *)q->name, sizeof(q->name), "Auto Exposure");
		q->minimum = 0;
		q->maximum = 3;
		q->default_value = V4L2_EXPOSURE_APERTURE_PRIORITY;
		return 0;
	case V4L2_CID_EXPOSURE_ABSOLUTE:
		q->type = V4L2_CTRL_TYPE_INTEGER;
		snprintf((char *)q->name, sizeof(q->name),
			 "Exposure Time, Absolute");
		q->minimum = 1;
		q->maximum = 20000;
		q->default_value = 100;
		if (f->ae != V4L2_EXPOSURE_MANUAL)
			q->flags = V4L2_CTRL_FLAG_INACTIVE;
		return 0;
	case V4L2_CID_ANALOGUE_GAIN:
		q->type = V4L2_CTRL_TYPE_INTEGER;
		snprintf((char *)q->name, sizeof(q->name), "Analogue Gain");
		q->minimum = 16;
		q->maximum = 256;
		q->default_value = 16;
		return 0;
	case V4L2_CID_BLACK_LEVEL:
		q->type = V4L2_CTRL_TYPE_INTEGER;
		snprintf((char *)q->name, sizeof(q->name), "Black Level");
		q->maximum = 4095;
		q->default_value = 64;
		q->flags = V4L2_CTRL_FLAG_READ_ONLY;
		return 0;
	}
	return fail(EINVAL);
}

static int ctrl_refused(const struct fake *f, uint32_t id)
{
	return (!strcmp(f->refuse, "exposure") &&
		id == V4L2_CID_EXPOSURE_ABSOLUTE) ||
	       (!strcmp(f->refuse, "gain") && id == V4L2_CID_ANALOGUE_GAIN) ||
	       (!strcmp(f->refuse, "auto") && id == V4L2_CID_EXPOSURE_AUTO);
}

static int s_ctrl(struct fake *f, struct v4l2_control *c)
{
	struct v4l2_queryctrl q = { .id = c->id };
	if (queryctrl(f, &q) < 0)
		return -1;
	if (q.flags & V4L2_CTRL_FLAG_READ_ONLY)
		return fail(EACCES);
	if (ctrl_refused(f, c->id))
		return fail(EACCES);
	int v = c->value < q.minimum   ? q.minimum
		: c->value > q.maximum ? q.maximum
				       : c->value;
	switch (c->id) {
	case V4L2_CID_EXPOSURE_AUTO:
		if (v == V4L2_EXPOSURE_MANUAL && !f->manual)
			return fail(EINVAL);
		if (v == V4L2_EXPOSURE_AUTO ||
		    v == V4L2_EXPOSURE_SHUTTER_PRIORITY)
			return fail(EINVAL); /* a UVC camera's usual menu */
		f->ae = v;
		return 0;
	case V4L2_CID_EXPOSURE_ABSOLUTE:
		f->exposure = v;
		break;
	case V4L2_CID_ANALOGUE_GAIN:
		f->gain = v;
		break;
	}
	/* The frame in progress keeps its settings; the sensor takes the new
	 * ones `latency` frames after it. */
	catch_up(f);
	if (f->sim && f->ae == V4L2_EXPOSURE_MANUAL)
		set_sim_exposure(f);
	return 0;
}

static int g_ctrl(struct fake *f, struct v4l2_control *c)
{
	switch (c->id) {
	case V4L2_CID_EXPOSURE_AUTO:
		c->value = f->ae;
		return 0;
	case V4L2_CID_EXPOSURE_ABSOLUTE:
		c->value = f->exposure;
		return 0;
	case V4L2_CID_ANALOGUE_GAIN:
		c->value = f->gain;
		return 0;
	case V4L2_CID_BLACK_LEVEL: {
		const struct glint_v4l2_format *g = cur_fmt(f);
		c->value = (int)to_bits(64, g ? g->bits : 12);
		return 0;
	}
	}
	return fail(EINVAL);
}

static void fill_format(struct fake *f, struct v4l2_format *fm)
{
	memset(&fm->fmt.pix, 0, sizeof(fm->fmt.pix));
	fm->fmt.pix.width = (uint32_t)f->width;
	fm->fmt.pix.height = (uint32_t)f->height;
	fm->fmt.pix.pixelformat = f->fourcc;
	fm->fmt.pix.field = V4L2_FIELD_NONE;
	fm->fmt.pix.bytesperline = (uint32_t)f->stride;
	fm->fmt.pix.sizeimage = (uint32_t)f->sizeimage;
	fm->fmt.pix.colorspace = V4L2_COLORSPACE_RAW;
}

static int reqbufs(struct fake *f, struct v4l2_requestbuffers *rb)
{
	if (rb->type != V4L2_BUF_TYPE_VIDEO_CAPTURE ||
	    rb->memory != V4L2_MEMORY_MMAP)
		return fail(EINVAL);
	if (f->streaming)
		return fail(EBUSY);
	if (f->mem) {
		munmap(f->mem, f->bufsize * (size_t)f->nbuf);
		f->mem = NULL;
	}
	f->nbuf = 0;
	f->ndone = 0;
	if (rb->count == 0)
		return 0;
	int n = rb->count < 2	       ? 2
		: rb->count > NBUF_MAX ? NBUF_MAX
				       : (int)rb->count;
	long page = sysconf(_SC_PAGESIZE);
	f->bufsize =
		(f->sizeimage + (size_t)page - 1) / (size_t)page * (size_t)page;
	if (ftruncate(f->fd, (off_t)(f->bufsize * (size_t)n)) < 0)
		return -1;
	f->mem = real_mmap(NULL, f->bufsize * (size_t)n, PROT_READ | PROT_WRITE,
			   MAP_SHARED, f->fd, 0);
	if (f->mem == MAP_FAILED) {
		f->mem = NULL;
		return -1;
	}
	f->nbuf = n;
	for (int i = 0; i < n; i++) {
		f->state[i] = B_CLIENT;
		memset(&f->meta[i], 0, sizeof(f->meta[i]));
	}
	rb->count = (uint32_t)n;
	return 0;
}

static void fill_buf(struct fake *f, int i, struct v4l2_buffer *b)
{
	*b = f->meta[i];
	b->index = (uint32_t)i;
	b->type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
	b->memory = V4L2_MEMORY_MMAP;
	b->length = (uint32_t)f->sizeimage;
	b->m.offset = (uint32_t)(f->bufsize * (size_t)i);
	b->flags = f->state[i] == B_QUEUED ? V4L2_BUF_FLAG_QUEUED
		   : f->state[i] == B_DONE ? V4L2_BUF_FLAG_DONE | b->flags
					   : b->flags;
}

/* Wait for a completed frame until `deadline` (real seconds); 1 if one
 * is there, 0 on timeout, -1 when unplugged. */
static int wait_frame(struct fake *f, double deadline)
{
	for (;;) {
		catch_up(f);
		if (f->unplugged)
			return -1;
		if (f->ndone)
			return 1;
		double left = deadline - now_real();
		if (left <= 0)
			return 0;
		double d = fmin(left, fmax(until_next(f), 1e-5));
		struct timespec ts = { (time_t)d,
				       (long)((d - (double)(time_t)d) * 1e9) };
		pthread_mutex_unlock(&lock);
		nanosleep(&ts, NULL);
		pthread_mutex_lock(&lock);
		if (!dev)
			return -1;
	}
}

static int dqbuf(struct fake *f, struct v4l2_buffer *b, int nonblock)
{
	int r = wait_frame(f, nonblock ? 0 : now_real() + 1e9);
	if (r < 0)
		return fail(ENODEV);
	if (r == 0)
		return fail(EAGAIN);
	int i = f->done[0];
	memmove(f->done, f->done + 1, (size_t)(--f->ndone) * sizeof(int));
	f->state[i] = B_CLIENT;
	long k = f->dequeued++;
	if (f->eio_at >= 0 && k >= f->eio_at)
		return fail(EIO);
	if (f->short_from >= 0 && k >= f->short_from)
		f->meta[i].bytesused = (uint32_t)(f->sizeimage / 2);
	fill_buf(f, i, b);
	b->flags &= ~(uint32_t)V4L2_BUF_FLAG_DONE;
	return 0;
}

static int handle_ioctl(struct fake *f, unsigned long req, void *arg)
{
	if (f->unplugged)
		return fail(ENODEV);
	catch_up(f);
	if (f->unplugged)
		return fail(ENODEV);
	switch (req) {
	case VIDIOC_QUERYCAP: {
		struct v4l2_capability *c = arg;
		memset(c, 0, sizeof(*c));
		snprintf((char *)c->driver, sizeof(c->driver), "fake-v4l2");
		snprintf((char *)c->card, sizeof(c->card), "glint fake camera");
		snprintf((char *)c->bus_info, sizeof(c->bus_info),
			 "platform:fake");
		c->version = 0x060100;
		c->device_caps = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_STREAMING;
		c->capabilities = c->device_caps | V4L2_CAP_DEVICE_CAPS;
		return 0;
	}
	case VIDIOC_ENUM_FMT: {
		struct v4l2_fmtdesc *d = arg;
		if (d->type != V4L2_BUF_TYPE_VIDEO_CAPTURE ||
		    d->index >= (uint32_t)f->nfmt)
			return fail(EINVAL);
		d->pixelformat = f->fmts[d->index];
		const struct glint_v4l2_format *g =
			glint_v4l2_format_find(d->pixelformat);
		snprintf((char *)d->description, sizeof(d->description), "%s",
			 g ? g->name : "Motion-JPEG");
		return 0;
	}
	case VIDIOC_ENUM_FRAMESIZES: {
		struct v4l2_frmsizeenum *s = arg;
		if (s->index > 0)
			return fail(EINVAL);
		s->type = V4L2_FRMSIZE_TYPE_DISCRETE;
		s->discrete.width = (uint32_t)f->width;
		s->discrete.height = (uint32_t)f->height;
		return 0;
	}
	case VIDIOC_G_FMT:
	case VIDIOC_S_FMT:
	case VIDIOC_TRY_FMT: {
		struct v4l2_format *fm = arg;
		if (fm->type != V4L2_BUF_TYPE_VIDEO_CAPTURE)
			return fail(EINVAL);
		if (req != VIDIOC_G_FMT) {
			uint32_t want = fm->fmt.pix.pixelformat,
				 got = f->fmts[0];
			for (int i = 0; i < f->nfmt; i++)
				if (f->fmts[i] == want)
					got = want;
			if (req == VIDIOC_S_FMT) {
				if (f->streaming || f->nbuf)
					return fail(EBUSY);
				f->fourcc = got;
				set_geometry(f);
			}
		}
		fill_format(f, fm);
		return 0;
	}
	case VIDIOC_G_PARM: {
		struct v4l2_streamparm *p = arg;
		memset(&p->parm, 0, sizeof(p->parm));
		p->parm.capture.capability = V4L2_CAP_TIMEPERFRAME;
		p->parm.capture.timeperframe.numerator = 1;
		p->parm.capture.timeperframe.denominator = 30;
		return 0;
	}
	case VIDIOC_QUERYCTRL:
		return queryctrl(f, arg);
	case VIDIOC_QUERYMENU: {
		struct v4l2_querymenu *m = arg;
		if (m->id != V4L2_CID_EXPOSURE_AUTO || m->index > 3)
			return fail(EINVAL);
		/* A UVC camera's menu: manual and aperture priority. */
		if (m->index == V4L2_EXPOSURE_MANUAL && f->manual) {
			snprintf((char *)m->name, sizeof(m->name), "Manual");
			return 0;
		}
		if (m->index == V4L2_EXPOSURE_APERTURE_PRIORITY) {
			snprintf((char *)m->name, sizeof(m->name),
				 "Aperture Priority");
			return 0;
		}
		return fail(EINVAL);
	}
	case VIDIOC_G_CTRL:
		return g_ctrl(f, arg);
	case VIDIOC_S_CTRL:
		return s_ctrl(f, arg);
	case VIDIOC_REQBUFS:
		return reqbufs(f, arg);
	case VIDIOC_QUERYBUF: {
		struct v4l2_buffer *b = arg;
		if (b->index >= (uint32_t)f->nbuf)
			return fail(EINVAL);
		fill_buf(f, (int)b->index, b);
		return 0;
	}
	case VIDIOC_QBUF: {
		struct v4l2_buffer *b = arg;
		if (b->index >= (uint32_t)f->nbuf ||
		    f->state[b->index] != B_CLIENT)
			return fail(EINVAL);
		f->state[b->index] = B_QUEUED;
		/* As vb2 does: the queued buffer's state is written back,
		 * its sequence number 0 (a client reading the frame's number
		 * after giving the buffer back gets 0, as on vivid). */
		f->meta[b->index].sequence = 0;
		f->meta[b->index].flags &= V4L2_BUF_FLAG_TIMESTAMP_MASK |
					   V4L2_BUF_FLAG_TSTAMP_SRC_MASK;
		fill_buf(f, (int)b->index, b);
		if (f->paused) { /* the next frame starts now */
			f->paused = 0;
			double t = (now_real() - f->t0_real) / f->timescale;
			if (t > f->next_start)
				f->t0_real = now_real() -
					     f->next_start * f->timescale;
		}
		return 0;
	}
	case VIDIOC_DQBUF:
		return dqbuf(f, arg, fcntl(f->fd, F_GETFL) & O_NONBLOCK);
	case VIDIOC_STREAMON:
		if (!f->nbuf)
			return fail(EINVAL);
		if (f->streaming)
			return 0;
		if (sensor_start(f) < 0)
			return fail(EIO);
		f->streaming = 1;
		return 0;
	case VIDIOC_STREAMOFF:
		f->streaming = 0;
		sensor_stop(f);
		for (int i = 0; i < f->nbuf; i++)
			f->state[i] = B_CLIENT;
		f->ndone = 0;
		return 0;
	}
	return fail(ENOTTY);
}

static int fake_open(const char *path, int flags)
{
	struct fake *f = calloc(1, sizeof(*f));
	if (!f)
		return fail(ENOMEM);
	configure_from_env(f);
	if (strcmp(path, f->path) != 0) {
		free(f);
		return -2; /* not ours */
	}
	if (dev) {
		free(f);
		return fail(EBUSY);
	}
	if (f->busy) {
		free(f);
		return fail(EBUSY);
	}
	f->fd = memfd_create("fake-v4l2", MFD_CLOEXEC);
	if (f->fd < 0) {
		free(f);
		return -1;
	}
	if (flags & O_NONBLOCK)
		fcntl(f->fd, F_SETFL, O_NONBLOCK);
	set_geometry(f);
	dev = f;
	return f->fd;
}

static int open_common(int (*real)(const char *, int, ...), const char *path,
		       int flags, mode_t mode)
{
	resolve();
	if (path && !strncmp(path, "/dev/video", 10)) {
		pthread_mutex_lock(&lock);
		int r = fake_open(path, flags);
		pthread_mutex_unlock(&lock);
		if (r != -2)
			return r;
	}
	return real(path, flags, mode);
}

__attribute__((visibility("default"))) int open(const char *path, int flags,
						...)
{
	mode_t mode = 0;
	if (flags & (O_CREAT | O_TMPFILE)) {
		va_list ap;
		va_start(ap, flags);
		mode = (mode_t)va_arg(ap, int);
		va_end(ap);
	}
	resolve();
	return open_common(real_open, path, flags, mode);
}

__attribute__((visibility("default"))) int open64(const char *path, int flags,
						  ...)
{
	mode_t mode = 0;
	if (flags & (O_CREAT | O_TMPFILE)) {
		va_list ap;
		va_start(ap, flags);
		mode = (mode_t)va_arg(ap, int);
		va_end(ap);
	}
	resolve();
	return open_common(real_open64 ? real_open64 : real_open, path, flags,
			   mode);
}

__attribute__((visibility("default"))) int close(int fd)
{
	resolve();
	pthread_mutex_lock(&lock);
	if (dev && fd == dev->fd) {
		struct fake *f = dev;
		sensor_stop(f);
		if (f->mem)
			munmap(f->mem, f->bufsize * (size_t)f->nbuf);
		dev = NULL;
		free(f);
	}
	pthread_mutex_unlock(&lock);
	return real_close(fd);
}

__attribute__((visibility("default"))) int ioctl(int fd, unsigned long req, ...)
{
	va_list ap;
	va_start(ap, req);
	void *arg = va_arg(ap, void *);
	va_end(ap);
	resolve();
	pthread_mutex_lock(&lock);
	if (dev && fd == dev->fd) {
		int r = handle_ioctl(dev, req, arg);
		pthread_mutex_unlock(&lock);
		return r;
	}
	pthread_mutex_unlock(&lock);
	return real_ioctl(fd, req, arg);
}

static void *mmap_common(void *(*real)(void *, size_t, int, int, int, off_t),
			 void *addr, size_t len, int prot, int flags, int fd,
			 off_t off)
{
	resolve();
	pthread_mutex_lock(&lock);
	if (dev && fd == dev->fd) {
		int ok = dev->nbuf && off >= 0 &&
			 (size_t)off % dev->bufsize == 0 &&
			 (size_t)off / dev->bufsize < (size_t)dev->nbuf &&
			 len <= dev->bufsize;
		pthread_mutex_unlock(&lock);
		if (!ok) {
			errno = EINVAL;
			return MAP_FAILED;
		}
		return real_mmap(addr, len, prot, flags, fd, off);
	}
	pthread_mutex_unlock(&lock);
	return real(addr, len, prot, flags, fd, off);
}

__attribute__((visibility("default"))) void *
mmap(void *addr, size_t len, int prot, int flags, int fd, off_t off)
{
	resolve();
	return mmap_common(real_mmap, addr, len, prot, flags, fd, off);
}

__attribute__((visibility("default"))) void *
mmap64(void *addr, size_t len, int prot, int flags, int fd, off_t off)
{
	resolve();
	return mmap_common(real_mmap64 ? real_mmap64 : real_mmap, addr, len,
			   prot, flags, fd, off);
}

__attribute__((visibility("default"))) int poll(struct pollfd *fds, nfds_t n,
						int timeout_ms)
{
	resolve();
	pthread_mutex_lock(&lock);
	for (nfds_t i = 0; dev && i < n; i++) {
		if (fds[i].fd != dev->fd)
			continue;
		double deadline = timeout_ms < 0
					  ? now_real() + 1e9
					  : now_real() + 1e-3 * timeout_ms;
		int r = dev->streaming ? wait_frame(dev, deadline) : -1;
		for (nfds_t j = 0; j < n; j++)
			fds[j].revents = 0;
		fds[i].revents = r > 0	 ? POLLIN | POLLRDNORM
				 : r < 0 ? POLLERR
					 : 0;
		pthread_mutex_unlock(&lock);
		return r != 0;
	}
	pthread_mutex_unlock(&lock);
	return real_poll(fds, n, timeout_ms);
}
