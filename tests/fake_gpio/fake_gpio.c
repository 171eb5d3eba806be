/* SPDX-License-Identifier: MIT */
/*
 * A fake GPIO character device for tests, as an LD_PRELOAD interposer: it
 * serves the kernel's v1 GPIO uAPI (what libgpiod 1.6 speaks) on
 * /dev/gpiochip0, so the libgpiod board backend runs unchanged.
 *
 * What it serves: GPIO_GET_CHIPINFO_IOCTL, GPIO_GET_LINEINFO_IOCTL,
 * GPIO_GET_LINEHANDLE_IOCTL (then GPIOHANDLE_SET/GET_LINE_VALUES_IOCTL on
 * the handle), GPIO_GET_LINEEVENT_IOCTL (a pipe that a thread fills with
 * struct gpioevent_data at scripted times; GET_LINE_VALUES on it), and
 * what libgpiod checks before it trusts a chip: lstat/stat (a character
 * device), access/open of /sys/bus/gpio/devices/gpiochip0/dev.  Values on
 * handles are logical; requests with GPIOHANDLE_REQUEST_ACTIVE_LOW invert
 * them to the physical level, as the kernel does; both-edge events report
 * the logical level (RISING = logical 1), as the v1 kernel code does.
 *
 * Configured by FAKE_GPIO (read at each open of the chip):
 *   lines=N            lines on gpiochip0 (default 32), named GPIO0..
 *   busy=OFF:WHO       line OFF already requested by consumer WHO
 *   press=AT:HOLD:B    a press of the line that requests edge events,
 *                      AT s after the request, held HOLD s, after B
 *                      bounces of 2 ms (several presses: press=..;..)
 *   vanish_after=N     after N ioctls the chip is gone (ENODEV)
 *   log=PATH           every output change as a JSON line
 *                      {"t", "offset", "value", "phys", "consumer"}
 */
/* Plain and 64-bit names are both defined here (meson builds with
 * _FILE_OFFSET_BITS=64, which would rename open to open64). */
#undef _FILE_OFFSET_BITS
#define _GNU_SOURCE
#include <linux/gpio.h>

#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ioctl.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <time.h>
#include <unistd.h>

#define CHIP_PATH   "/dev/gpiochip0"
#define SYSFS_DEV   "/sys/bus/gpio/devices/gpiochip0/dev"
#define MAX_LINES   64
#define MAX_FDS	    256
#define MAX_PRESSES 16

static int (*real_open)(const char *, int, ...);
static int (*real_open64)(const char *, int, ...);
static int (*real_close)(int);
static int (*real_ioctl)(int, unsigned long, ...);
static int (*real_lstat)(const char *, struct stat *);
static int (*real_stat)(const char *, struct stat *);
static int (*real_access)(const char *, int);

enum fd_kind { FD_NONE, FD_CHIP, FD_HANDLE, FD_EVENT };

struct line {
	int requested, output, active_low, value; /* value: logical */
	char consumer[GPIO_MAX_NAME_SIZE];
};

struct fdent {
	enum fd_kind kind;
	int nlines;
	unsigned offsets[GPIOHANDLES_MAX];
	int write_end; /* event: the pipe's writing end */
	pthread_t thread;
	int stop;
};

static pthread_mutex_t lock = PTHREAD_MUTEX_INITIALIZER;
static struct line lines[MAX_LINES];
static struct fdent fds[MAX_FDS];
static int nlines = 32;
static long ioctls, vanish_after = -1;
static char log_path[1024];
static double press_at[MAX_PRESSES], press_hold[MAX_PRESSES];
static int press_bounces[MAX_PRESSES], npresses;
static int configured;

__attribute__((constructor)) static void init(void)
{
	if (real_open)
		return;
	real_open = (int (*)(const char *, int, ...))dlsym(RTLD_NEXT, "open");
	real_open64 =
		(int (*)(const char *, int, ...))dlsym(RTLD_NEXT, "open64");
	real_close = (int (*)(int))dlsym(RTLD_NEXT, "close");
	real_ioctl =
		(int (*)(int, unsigned long, ...))dlsym(RTLD_NEXT, "ioctl");
	real_lstat =
		(int (*)(const char *, struct stat *))dlsym(RTLD_NEXT, "lstat");
	real_stat =
		(int (*)(const char *, struct stat *))dlsym(RTLD_NEXT, "stat");
	real_access = (int (*)(const char *, int))dlsym(RTLD_NEXT, "access");
}

static double now_s(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* (Re)read FAKE_GPIO; lines keep their state within a process unless
 * the configuration changed. */
static void configure(void)
{
	static char last[1024];
	const char *env = getenv("FAKE_GPIO");
	if (!env)
		env = "";
	if (configured && !strcmp(last, env))
		return;
	snprintf(last, sizeof(last), "%s", env);
	configured = 1;
	memset(lines, 0, sizeof(lines));
	nlines = 32;
	vanish_after = -1;
	ioctls = 0;
	log_path[0] = '\0';
	npresses = 0;
	char buf[1024];
	snprintf(buf, sizeof(buf), "%s", env);
	for (char *save = NULL, *kv = strtok_r(buf, ",", &save); kv;
	     kv = strtok_r(NULL, ",", &save)) {
		char who[GPIO_MAX_NAME_SIZE];
		unsigned off;
		if (sscanf(kv, "lines=%d", &nlines) == 1) {
			if (nlines < 1 || nlines > MAX_LINES)
				nlines = 32;
		} else if (sscanf(kv, "busy=%u:%31s", &off, who) == 2 &&
			   off < MAX_LINES) {
			lines[off].requested = 1;
			snprintf(lines[off].consumer,
				 sizeof(lines[off].consumer), "%s", who);
		} else if (sscanf(kv, "vanish_after=%ld", &vanish_after) == 1) {
		} else if (!strncmp(kv, "log=", 4)) {
			snprintf(log_path, sizeof(log_path), "%s", kv + 4);
		} else if (!strncmp(kv, "press=", 6)) {
			char *p = kv + 6;
			while (*p && npresses < MAX_PRESSES) {
				int n = 0;
				if (sscanf(p, "%lf:%lf:%d%n",
					   &press_at[npresses],
					   &press_hold[npresses],
					   &press_bounces[npresses], &n) != 3)
					break;
				npresses++;
				p += n;
				if (*p == ';')
					p++;
			}
		}
	}
}

static int chip_path(const char *path)
{
	return path && !strcmp(path, CHIP_PATH);
}

static int new_fd(enum fd_kind kind, int fd)
{
	if (fd < 0 || fd >= MAX_FDS)
		return -1;
	memset(&fds[fd], 0, sizeof(fds[fd]));
	fds[fd].kind = kind;
	fds[fd].write_end = -1;
	return fd;
}

static int sysfs_fd(void)
{
	int p[2];
	if (pipe(p) < 0)
		return -1;
	char dev[16];
	int n = snprintf(dev, sizeof(dev), "254:0\n");
	if (write(p[1], dev, (size_t)n) != n) {
		real_close(p[0]);
		real_close(p[1]);
		return -1;
	}
	real_close(p[1]);
	return p[0];
}

static int do_open(int (*fn)(const char *, int, ...), const char *path,
		   int flags, mode_t mode)
{
	if (chip_path(path)) {
		pthread_mutex_lock(&lock);
		configure();
		int fd = fn("/dev/null", O_RDWR | (flags & O_CLOEXEC));
		if (fd >= 0 && new_fd(FD_CHIP, fd) < 0) {
			real_close(fd);
			fd = -1;
			errno = EMFILE;
		}
		pthread_mutex_unlock(&lock);
		return fd;
	}
	if (path && !strcmp(path, SYSFS_DEV))
		return sysfs_fd();
	return fn(path, flags, mode);
}

__attribute__((visibility("default"))) int open(const char *path, int flags,
						...)
{
	init();
	mode_t mode = 0;
	if (flags & (O_CREAT | O_TMPFILE)) {
		va_list ap;
		va_start(ap, flags);
		mode = (mode_t)va_arg(ap, int);
		va_end(ap);
	}
	return do_open(real_open, path, flags, mode);
}

__attribute__((visibility("default"))) int open64(const char *path, int flags,
						  ...)
{
	init();
	mode_t mode = 0;
	if (flags & (O_CREAT | O_TMPFILE)) {
		va_list ap;
		va_start(ap, flags);
		mode = (mode_t)va_arg(ap, int);
		va_end(ap);
	}
	return do_open(real_open64, path, flags, mode);
}

static void fake_stat(struct stat *st)
{
	memset(st, 0, sizeof(*st));
	st->st_mode = S_IFCHR | 0660;
	st->st_rdev = makedev(254, 0);
}

__attribute__((visibility("default"))) int lstat(const char *path,
						 struct stat *st)
{
	init();
	if (chip_path(path)) {
		fake_stat(st);
		return 0;
	}
	return real_lstat(path, st);
}

__attribute__((visibility("default"))) int stat(const char *path,
						struct stat *st)
{
	init();
	if (chip_path(path)) {
		fake_stat(st);
		return 0;
	}
	return real_stat(path, st);
}

__attribute__((visibility("default"))) int access(const char *path, int mode)
{
	init();
	if (!strcmp(path, SYSFS_DEV) || chip_path(path))
		return 0;
	return real_access(path, mode);
}

static void log_output(unsigned off)
{
	if (!log_path[0])
		return;
	FILE *f = fopen(log_path, "a");
	if (!f)
		return;
	const struct line *l = &lines[off];
	fprintf(f,
		"{\"t\": %.6f, \"offset\": %u, \"value\": %d, \"phys\": %d, "
		"\"consumer\": \"%s\"}\n",
		now_s(), off, l->value, l->value ^ l->active_low, l->consumer);
	fclose(f);
}

static void release_fd(int fd)
{
	struct fdent *e = &fds[fd];
	if (e->kind == FD_HANDLE || e->kind == FD_EVENT)
		for (int i = 0; i < e->nlines; i++) {
			struct line *l = &lines[e->offsets[i]];
			l->requested = 0;
			l->output = 0;
			l->consumer[0] = '\0';
		}
	e->kind = FD_NONE;
}

__attribute__((visibility("default"))) int close(int fd)
{
	init();
	if (fd >= 0 && fd < MAX_FDS) {
		pthread_t th = 0;
		int wend = -1;
		pthread_mutex_lock(&lock);
		if (fds[fd].kind == FD_EVENT) {
			fds[fd].stop = 1;
			th = fds[fd].thread;
			wend = fds[fd].write_end;
		}
		if (fds[fd].kind != FD_NONE)
			release_fd(fd);
		pthread_mutex_unlock(&lock);
		if (th) {
			pthread_join(th, NULL);
			real_close(wend);
		}
	}
	return real_close(fd);
}

struct press_job {
	int fd, write_end;
	unsigned off;
	double t0;
};

static void emit(struct press_job *j, double t, int v)
{
	for (;;) {
		double dt = t - now_s();
		pthread_mutex_lock(&lock);
		int stop = fds[j->fd].stop;
		pthread_mutex_unlock(&lock);
		if (stop)
			return;
		if (dt <= 0)
			break;
		struct timespec ts = { 0,
				       (long)((dt < 0.01 ? dt : 0.01) * 1e9) };
		nanosleep(&ts, NULL);
	}
	pthread_mutex_lock(&lock);
	lines[j->off].value = v;
	pthread_mutex_unlock(&lock);
	struct gpioevent_data ev;
	memset(&ev, 0, sizeof(ev));
	ev.timestamp = (__u64)(now_s() * 1e9);
	ev.id = v ? GPIOEVENT_EVENT_RISING_EDGE : GPIOEVENT_EVENT_FALLING_EDGE;
	if (write(j->write_end, &ev, sizeof(ev)) != sizeof(ev)) {
		/* the reader is gone */
	}
}

static void *press_main(void *arg)
{
	struct press_job *j = arg;
	for (int i = 0; i < npresses; i++) {
		double t = j->t0 + press_at[i];
		for (int k = 0; k < 2 * press_bounces[i]; k++)
			emit(j, t + 0.002 * k, !(k & 1));
		t += 0.002 * 2 * press_bounces[i];
		emit(j, t, 1);
		emit(j, t + press_hold[i], 0);
	}
	free(j);
	return NULL;
}

static int vanished(void)
{
	return vanish_after >= 0 && ++ioctls > vanish_after;
}

static int chip_ioctl(int fd, unsigned long req, void *arg)
{
	if (vanished()) {
		errno = ENODEV;
		return -1;
	}
	if (req == GPIO_GET_CHIPINFO_IOCTL) {
		struct gpiochip_info *ci = arg;
		memset(ci, 0, sizeof(*ci));
		snprintf(ci->name, sizeof(ci->name), "gpiochip0");
		snprintf(ci->label, sizeof(ci->label), "glint-fake");
		ci->lines = (unsigned)nlines;
		return 0;
	}
	if (req == GPIO_GET_LINEINFO_IOCTL) {
		struct gpioline_info *li = arg;
		if (li->line_offset >= (unsigned)nlines) {
			errno = EINVAL;
			return -1;
		}
		const struct line *l = &lines[li->line_offset];
		unsigned off = li->line_offset;
		memset(li, 0, sizeof(*li));
		li->line_offset = off;
		snprintf(li->name, sizeof(li->name), "GPIO%u", off);
		snprintf(li->consumer, sizeof(li->consumer), "%s", l->consumer);
		li->flags = (l->requested ? GPIOLINE_FLAG_KERNEL : 0) |
			    (l->output ? GPIOLINE_FLAG_IS_OUT : 0) |
			    (l->active_low ? GPIOLINE_FLAG_ACTIVE_LOW : 0);
		return 0;
	}
	if (req == GPIO_GET_LINEHANDLE_IOCTL) {
		struct gpiohandle_request *hr = arg;
		if (hr->lines == 0 || hr->lines > GPIOHANDLES_MAX) {
			errno = EINVAL;
			return -1;
		}
		for (unsigned i = 0; i < hr->lines; i++) {
			if (hr->lineoffsets[i] >= (unsigned)nlines) {
				errno = EINVAL;
				return -1;
			}
			if (lines[hr->lineoffsets[i]].requested) {
				errno = EBUSY;
				return -1;
			}
		}
		int h = real_open("/dev/null", O_RDWR | O_CLOEXEC);
		if (new_fd(FD_HANDLE, h) < 0) {
			if (h >= 0)
				real_close(h);
			errno = EMFILE;
			return -1;
		}
		fds[h].nlines = (int)hr->lines;
		for (unsigned i = 0; i < hr->lines; i++) {
			unsigned off = hr->lineoffsets[i];
			struct line *l = &lines[off];
			fds[h].offsets[i] = off;
			l->requested = 1;
			l->output = !!(hr->flags & GPIOHANDLE_REQUEST_OUTPUT);
			l->active_low =
				!!(hr->flags & GPIOHANDLE_REQUEST_ACTIVE_LOW);
			snprintf(l->consumer, sizeof(l->consumer), "%s",
				 hr->consumer_label);
			if (l->output) {
				l->value = hr->default_values[i];
				log_output(off);
			}
		}
		hr->fd = h;
		return 0;
	}
	if (req == GPIO_GET_LINEEVENT_IOCTL) {
		struct gpioevent_request *er = arg;
		int p[2];
		if (er->lineoffset >= (unsigned)nlines) {
			errno = EINVAL;
			return -1;
		}
		if (lines[er->lineoffset].requested) {
			errno = EBUSY;
			return -1;
		}
		if (pipe2(p, O_CLOEXEC) < 0)
			return -1;
		if (new_fd(FD_EVENT, p[0]) < 0) {
			real_close(p[0]);
			real_close(p[1]);
			errno = EMFILE;
			return -1;
		}
		struct line *l = &lines[er->lineoffset];
		l->requested = 1;
		l->active_low =
			!!(er->handleflags & GPIOHANDLE_REQUEST_ACTIVE_LOW);
		l->value = 0;
		snprintf(l->consumer, sizeof(l->consumer), "%s",
			 er->consumer_label);
		fds[p[0]].nlines = 1;
		fds[p[0]].offsets[0] = er->lineoffset;
		fds[p[0]].write_end = p[1];
		struct press_job *j = malloc(sizeof(*j));
		*j = (struct press_job){ p[0], p[1], er->lineoffset, now_s() };
		pthread_create(&fds[p[0]].thread, NULL, press_main, j);
		er->fd = p[0];
		(void)fd;
		return 0;
	}
	errno = ENOTTY;
	return -1;
}

static int handle_ioctl(int fd, unsigned long req, void *arg)
{
	struct fdent *e = &fds[fd];
	if (vanished()) {
		errno = ENODEV;
		return -1;
	}
	struct gpiohandle_data *d = arg;
	if (req == GPIOHANDLE_GET_LINE_VALUES_IOCTL) {
		memset(d, 0, sizeof(*d));
		for (int i = 0; i < e->nlines; i++)
			d->values[i] = (__u8)lines[e->offsets[i]].value;
		return 0;
	}
	if (req == GPIOHANDLE_SET_LINE_VALUES_IOCTL && e->kind == FD_HANDLE) {
		for (int i = 0; i < e->nlines; i++) {
			struct line *l = &lines[e->offsets[i]];
			if (!l->output) {
				errno = EPERM;
				return -1;
			}
			int v = !!d->values[i];
			if (v != l->value) {
				l->value = v;
				log_output(e->offsets[i]);
			}
		}
		return 0;
	}
	errno = ENOTTY;
	return -1;
}

__attribute__((visibility("default"))) int ioctl(int fd, unsigned long req, ...)
{
	init();
	va_list ap;
	va_start(ap, req);
	void *arg = va_arg(ap, void *);
	va_end(ap);
	if (fd >= 0 && fd < MAX_FDS) {
		pthread_mutex_lock(&lock);
		enum fd_kind k = fds[fd].kind;
		int ret = -2;
		if (k == FD_CHIP)
			ret = chip_ioctl(fd, req, arg);
		else if (k == FD_HANDLE || k == FD_EVENT)
			ret = handle_ioctl(fd, req, arg);
		int e = errno;
		pthread_mutex_unlock(&lock);
		if (ret != -2) {
			errno = e;
			return ret;
		}
	}
	return real_ioctl(fd, req, arg);
}
