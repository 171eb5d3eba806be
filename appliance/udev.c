/* SPDX-License-Identifier: MIT */
/* A udev rules file scoped to one rig's devices (udev.h). */
#define _GNU_SOURCE
#include "appliance/udev.h"

#include "core/error.h"

#include <dirent.h>
#include <errno.h>
#include <limits.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>

static const char *sysfs(void)
{
	const char *s = getenv("GLINT_SYSFS");
	return s && *s ? s : "/sys";
}

/* A value udev matches literally: no quotes, globs or spaces. */
static int plain(const char *s)
{
	if (!*s)
		return 0;
	for (; *s; s++)
		if (!((*s >= 'a' && *s <= 'z') || (*s >= 'A' && *s <= 'Z') ||
		      (*s >= '0' && *s <= '9') || strchr("._:@+-,", *s)))
			return 0;
	return 1;
}

/* name into out[n] whole, or -ENAMETOOLONG. */
static int copy_name(const char *name, char *out, size_t n)
{
	size_t len = strlen(name);
	if (len >= n)
		return -ENAMETOOLONG;
	memcpy(out, name, len + 1);
	return 0;
}

/* The kernel name of the device `link` (a sysfs device folder's "device"
 * link) points to. */
static int parent_name(const char *link, char *out, size_t n)
{
	char real[PATH_MAX];
	if (!realpath(link, real))
		return -errno;
	const char *base = strrchr(real, '/');
	return copy_name(base ? base + 1 : real, out, n);
}

/* The kernel name of the device that bus device `name` (a GPIO chip, a
 * media controller: devices of a bus, not a class, have no "device" link;
 * their folder lies in their parent's) hangs from: its controller (a
 * platform device such as fe200000.gpio or vimc.0, a USB interface,
 * gpio-sim.0). */
static int bus_parent(const char *bus, const char *name, char *out, size_t n)
{
	char path[PATH_MAX], real[PATH_MAX];
	snprintf(path, sizeof(path), "%s/bus/%s/devices/%s", sysfs(), bus,
		 name);
	if (!realpath(path, real))
		return -errno;
	char *slash = strrchr(real, '/');
	if (!slash)
		return -ENOENT;
	*slash = 0;
	slash = strrchr(real, '/');
	return copy_name(slash ? slash + 1 : real, out, n);
}

struct text {
	char *s;
	size_t len;
	int failed;
};

static void add(struct text *t, const char *fmt, ...)
	__attribute__((format(printf, 2, 3)));

static void add(struct text *t, const char *fmt, ...)
{
	va_list ap;
	char *line;
	va_start(ap, fmt);
	int n = vasprintf(&line, fmt, ap);
	va_end(ap);
	char *grown = n < 0 ? NULL : realloc(t->s, t->len + (size_t)n + 1);
	if (!grown) {
		if (n >= 0)
			free(line);
		t->failed = 1;
		return;
	}
	memcpy(grown + t->len, line, (size_t)n + 1);
	t->s = grown;
	t->len += (size_t)n;
	free(line);
}

static void grant(struct text *t, const char *match, const char *group)
{
	add(t, "%s, RUN+=\"/usr/bin/setfacl -m g:%s:rw $devnode\"\n", match,
	    group);
}

static int v4l2_camera(struct text *t, const char *dev, const char *group)
{
	struct stat st;
	char link[PATH_MAX], parent[256];

	if (!dev || !*dev)
		return glint_error_set(EINVAL,
				       "udev rules: the rig file names no V4L2 "
				       "device (camera.device, e.g. "
				       "/dev/v4l/by-path/...): the rule is for "
				       "one camera");
	if (stat(dev, &st) < 0)
		return glint_error_set(errno, "udev rules: camera %s: %s", dev,
				       strerror(errno));
	if (!S_ISCHR(st.st_mode))
		return glint_error_set(ENODEV,
				       "udev rules: camera %s: not a device "
				       "node",
				       dev);
	snprintf(link, sizeof(link), "%s/dev/char/%u:%u/device", sysfs(),
		 major(st.st_rdev), minor(st.st_rdev));
	int ret = parent_name(link, parent, sizeof(parent));
	if (ret < 0)
		return glint_error_set(
			-ret,
			"udev rules: camera %s: no parent device "
			"in sysfs (%s): %s",
			dev, link, strerror(-ret));
	if (!plain(parent))
		return glint_error_set(EINVAL,
				       "udev rules: camera %s: its parent "
				       "device '%s' is no name udev matches "
				       "literally",
				       dev, parent);
	add(t,
	    "# the camera, %s (V4L2): the video, sub-device and media "
	    "nodes of its\n# device, %s\n",
	    dev, parent);
	char match[512];
	snprintf(match, sizeof(match),
		 "SUBSYSTEM==\"video4linux|media\", KERNELS==\"%s\"", parent);
	grant(t, match, group);
	return 0;
}

/* Does the libcamera id hold `name` as a word of its path ("platform/
 * vimc.0 Sensor B" holds vimc.0)? */
static int id_names(const char *id, const char *name)
{
	size_t n = strlen(name);
	for (const char *p = strstr(id, name); p; p = strstr(p + 1, name)) {
		char before = p == id ? '/' : p[-1], after = p[n];
		if ((before == '/' || before == ' ') &&
		    (after == 0 || after == ' ' || after == '/'))
			return 1;
	}
	return 0;
}

static int libcamera_camera(struct text *t, const char *id, const char *group)
{
	char dir[PATH_MAX], parent[256];
	char seen[8][256];
	int nseen = 0;

	if (!id || !*id)
		return glint_error_set(EINVAL,
				       "udev rules: the rig file names no "
				       "libcamera camera (camera.device: its "
				       "id, from glint cameras): the rule is "
				       "for one camera");
	snprintf(dir, sizeof(dir), "%s/bus/media/devices", sysfs());
	DIR *d = opendir(dir);
	if (!d)
		return glint_error_set(ENODEV, "udev rules: %s: %s", dir,
				       strerror(errno));
	struct dirent *e;
	while ((e = readdir(d)) && nseen < 8) {
		if (e->d_name[0] == '.')
			continue;
		if (bus_parent("media", e->d_name, parent, sizeof(parent)) <
			    0 ||
		    !plain(parent) || !id_names(id, parent))
			continue;
		int dup = 0;
		for (int k = 0; k < nseen; k++)
			dup |= !strcmp(seen[k], parent);
		if (!dup)
			snprintf(seen[nseen++], sizeof(seen[0]), "%s", parent);
	}
	closedir(d);
	if (!nseen)
		return glint_error_set(ENODEV,
				       "udev rules: camera '%s' (libcamera): "
				       "no media device under %s is of a "
				       "device its id names; name the camera "
				       "by its V4L2 node (camera.backend "
				       "v4l2) or write the rule by hand "
				       "(docs/rig.md)",
				       id, dir);
	for (int k = 0; k < nseen; k++) {
		add(t,
		    "# the camera, '%s' (libcamera): the media, video and "
		    "sub-device\n# nodes of its device, %s\n",
		    id, seen[k]);
		char match[512];
		snprintf(match, sizeof(match),
			 "SUBSYSTEM==\"video4linux|media\", KERNELS==\"%s\"",
			 seen[k]);
		grant(t, match, group);
	}
	add(t, "# the DMA heaps libcamera allocates frame buffers from\n");
	grant(t, "SUBSYSTEM==\"dma_heap\"", group);
	return 0;
}

static int gpio_chips(struct text *t, const struct glint_rig *rig,
		      const struct glint_board *board, const char *group)
{
	char parents[GLINT_ROLE_COUNT][256];
	int n = 0;

	for (int r = 0; r < GLINT_ROLE_COUNT; r++) {
		char name[64], label[64], parent[256];
		if (!rig->board.lines[r].used)
			continue;
		int ret = glint_board_chip(board, (enum glint_role)r, name,
					   sizeof(name), label, sizeof(label));
		if (ret < 0)
			return ret;
		ret = bus_parent("gpio", name, parent, sizeof(parent));
		if (ret < 0)
			return glint_error_set(-ret,
					       "udev rules: GPIO chip %s: no "
					       "device in %s/bus/gpio/devices: "
					       "%s",
					       name, sysfs(), strerror(-ret));
		if (!plain(parent))
			return glint_error_set(
				EINVAL,
				"udev rules: GPIO chip %s: its "
				"controller '%s' is no name udev "
				"matches literally",
				name, parent);
		int dup = 0;
		for (int k = 0; k < n; k++)
			dup |= !strcmp(parents[k], parent);
		if (dup)
			continue;
		snprintf(parents[n], sizeof(parents[0]), "%s", parent);
		add(t,
		    "# GPIO chip %s (\"%s\"): the chips of its controller, "
		    "%s\n",
		    name, label, parent);
		char match[512];
		snprintf(match, sizeof(match),
			 "SUBSYSTEM==\"gpio\", KERNEL==\"gpiochip*\", "
			 "KERNELS==\"%s\"",
			 parent);
		grant(t, match, group);
		n++;
	}
	return 0;
}

int glint_udev_rules(const struct glint_rig *rig,
		     const struct glint_board *board, const char *group,
		     char **text)
{
	struct text t = { NULL, 0, 0 };
	const char *cam = rig->capture.backend ? rig->capture.backend : "sim";
	int has_gpio = board && rig->has_board &&
		       strcmp(rig->board.backend, "sim") != 0;
	int ret = 0;

	*text = NULL;
	if (!plain(group))
		return glint_error_set(EINVAL, "udev rules: group '%s'", group);
	if (!strcmp(cam, "sim") && !has_gpio)
		return glint_error_set(EINVAL,
				       "udev rules: %s: the simulated camera "
				       "and board use no device; no rule is "
				       "needed",
				       rig->path);
	add(&t,
	    "# written by glint check-rig --udev-rules for %s\n"
	    "# (docs/rig.md): members of the %s group get read-write access "
	    "to this\n# rig's devices and no others, as POSIX ACLs (the "
	    "nodes keep their owners,\n# groups and modes; needs the acl "
	    "package's setfacl).\n"
	    "ACTION==\"remove\", GOTO=\"glint_end\"\n",
	    rig->path, group);
	if (!strcmp(cam, "v4l2"))
		ret = v4l2_camera(&t, rig->capture.device, group);
	else if (!strcmp(cam, "libcamera"))
		ret = libcamera_camera(&t, rig->capture.device, group);
	if (ret == 0 && has_gpio)
		ret = gpio_chips(&t, rig, board, group);
	add(&t, "LABEL=\"glint_end\"\n");
	if (ret == 0 && t.failed)
		ret = glint_error_set(ENOMEM, "udev rules: out of memory");
	if (ret < 0) {
		free(t.s);
		return ret;
	}
	*text = t.s;
	return 0;
}
