/* SPDX-License-Identifier: MIT */
#ifndef GLINT_APPLIANCE_UDEV_H
#define GLINT_APPLIANCE_UDEV_H

/*
 * A udev rules file that gives one group (the rig daemon's, glint-dev)
 * read-write access to this rig's devices and no others, as POSIX ACLs
 * (the nodes keep their owners, groups and modes):
 *
 *  - a V4L2 camera (its device node in the rig file): every video4linux
 *    and media node of the same parent device (the USB interface, the
 *    platform device: `KERNELS=="1-1.3:1.0"`), so its video, sub-device
 *    and media-controller nodes and nothing of another camera;
 *  - a libcamera camera (its id in the rig file): the media devices whose
 *    parent device the id names (e.g. "platform/vimc.0 Sensor B" names
 *    vimc.0), with their video and sub-device nodes; and the DMA heaps
 *    libcamera allocates frame buffers from;
 *  - each GPIO chip the board's lines are on, by the device it hangs from
 *    (its controller: `KERNELS=="fe200000.gpio"`, a USB interface), which
 *    holds when the chips are numbered in another order at boot (the
 *    chip's label is no attribute of its device node).
 *
 * The simulated camera and board need no device: a rig of only those
 * gets an error saying so.  The parent devices are read from sysfs
 * (GLINT_SYSFS, default /sys).
 *
 * Errors: a negative errno with glint_error_msg() naming the device and
 * what to do.  Threads: re-entrant.  Who frees: the caller frees *text.
 */

#include "appliance/rig.h"
#include "board/board.h"

/* The rules for `rig` (its board open as `board`, NULL when it has none)
 * and group `group`, as a text: *text (malloc'd). */
int glint_udev_rules(const struct glint_rig *rig,
		     const struct glint_board *board, const char *group,
		     char **text);

#endif
