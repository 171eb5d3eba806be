#!/usr/bin/env python3
"""Read gpio-sim output lines back from the kernel while glint drives them.

usage: sample_lines.py [--world PATH STEPS_PER_TURN] LOG NAME=SYSFS_VALUE_FILE...
       sample_lines.py --explain LOG GLINT_JSON_LOG

Every value the kernel sets on the named lines comes from its own record,
the gpio_value trace event (tracefs), so no change is missed however the
VM's CPUs are scheduled: polling sysfs under TCG on a loaded host missed
50 ms step pulses. Each line's first level is read from its gpio-sim sysfs
`value` (the physical level). Every change is written as a JSON line
{"t": seconds on CLOCK_MONOTONIC (the event's kernel time), "line": NAME,
"value": 0|1} to LOG, flushed at once so a reader sees it while it runs.
Runs until SIGTERM, then reads what the kernel still holds before it exits.

With --world, it also plays the rig's hardware for the simulated camera:
the lamps follow the `lights` line and the turntable turns 360/STEPS_PER_TURN
degrees at each rising edge of `step` (positive with `dir` high), and PATH
says "LIGHTS DEGREES" (the sim camera's world=PATH), replaced whole once
per batch of events read: one event while it keeps up, and one write for
all it missed when a loaded host has slowed the VM (written per event, it
fell 0.26 s behind over 20 steps here, seconds in CI). Run it at a
real-time priority so that the world is written as soon as the kernel has
the change (test_gpio_sim.sh). Each world written is logged too ({"t": the
change's time, "world": "LIGHTS DEGREES", "written": when the file was
replaced}), and --explain lays a failed run's log next to glint's on one
clock.
"""
import calendar
import glob
import json
import os
import re
import select
import signal
import sys
import time

TRACE = "/sys/kernel/tracing"
EVENT = TRACE + "/events/gpio/gpio_value"


stopping = [False]


def on_term(*_):
    stopping[0] = True


def put(path, text):
    with open(path, "w") as f:
        f.write(text)


def chip_base(chip_dir):
    """The global GPIO number of the chip's line 0, which the trace event
    names lines by: the legacy class device whose parent is the chip's."""
    parent = os.path.realpath(os.path.join(chip_dir, ".."))
    for d in glob.glob("/sys/class/gpio/gpiochip*"):
        if os.path.realpath(os.path.join(d, "device")) == parent:
            return int(open(os.path.join(d, "base")).read())
    sys.exit("sample_lines: no /sys/class/gpio entry for %s" % chip_dir)


def start_trace():
    if not os.path.exists(EVENT):
        os.makedirs(TRACE, exist_ok=True)
        if os.system("mount -t tracefs nodev " + TRACE) != 0:
            sys.exit("sample_lines: cannot mount tracefs")
    put(EVENT + "/enable", "0")
    put(TRACE + "/trace", "")  # nothing left from an earlier reader
    put(TRACE + "/trace_clock", "mono")
    put(EVENT + "/filter", "get == 0")  # values set, not read
    put(EVENT + "/enable", "1")


def explain(lines_log, glint_log):
    """After a failed run: what the camera was shown and when, step pulses
    counted, and glint's own steps, on one clock."""
    ev = [json.loads(l) for l in open(lines_log)]
    off = next((e["wall"] - e["t"] for e in ev if "wall" in e), 0.0)
    rows = []
    for e in ev:
        if "world" in e:
            rows.append((e["t"] + off, "world %s (written %+.3f s after the line moved)"
                         % (e["world"], e["written"] - e["t"])))
    rises = [e["t"] + off for e in ev if e.get("line") == "step" and e["value"] == 1]
    t0 = ev[0]["t"] + off
    print("  sampler: %d step pulses, first at %.3f s, last at %.3f s" %
          (len(rises), (rises[0] if rises else t0) - t0,
           (rises[-1] if rises else t0) - t0))
    for l in open(glint_log):
        try:
            g = json.loads(l)
            t = calendar.timegm(time.strptime(g["time"][:19], "%Y-%m-%dT%H:%M:%S"))
            t += float(g["time"][19:-1] or 0)
        except (ValueError, KeyError):
            continue
        rows.append((t, "glint: " + g["msg"][:110]))
    for t, what in sorted(rows):
        print("  %8.3f %s" % (t - t0, what))


def main():
    args = sys.argv[1:]
    if args[0] == "--explain":
        return explain(args[1], args[2])
    world = None
    if args[0] == "--world":
        world, per_turn = args[1], int(args[2])
        args = args[3:]
    log = open(args[0], "w")
    state = {"lights": 0, "deg": 0.0, "dir": 0, "step": 0}
    out = []  # log lines of this batch
    moved = [None]  # the time of the batch's last change to the world

    def write_world(t):
        tmp = world + ".tmp"
        text = "%d %.6f" % (state["lights"], state["deg"])
        put(tmp, text + "\n")
        os.replace(tmp, world)
        # When the camera could first see it, against when the line moved.
        out.append(json.dumps({"t": t, "world": text,
                               "written": time.monotonic()}))

    def change(name, v, t, last):
        if v == last.get(name):
            return
        prev = last.get(name)
        last[name] = v
        out.append(json.dumps({"t": t, "line": name, "value": v}))
        if world and name in state:
            if name == "step" and v == 1 and prev is not None:
                state["deg"] += (360.0 if state["dir"] else -360.0) / per_turn
                moved[0] = t
            if name == "lights":
                moved[0] = t
            state[name] = v

    def end_batch():
        # One world written per batch of events: a sampler that fell
        # behind (a loaded host slows the VM's Python) catches up at once
        # instead of replaying every step to the camera late.
        if world and moved[0] is not None:
            write_world(moved[0])
            moved[0] = None
        if out:
            log.write("\n".join(out) + "\n")
            log.flush()
            del out[:]

    signal.signal(signal.SIGTERM, on_term)
    start_trace()
    by_gpio, last = {}, {}
    lines = []
    for arg in args[1:]:  # in order: list dir before step
        name, path = arg.split("=", 1)
        offset = int(re.search(r"sim_gpio(\d+)", path).group(1))
        chip = os.path.dirname(os.path.dirname(path))
        by_gpio[chip_base(chip) + offset] = name
        lines.append((name, path))
    # The wall clock at one monotonic instant, to line this log up with
    # glint's (explain()).
    out.append(json.dumps({"t": time.monotonic(), "wall": time.time()}))
    if world:
        write_world(time.monotonic())
    # Trace on first, then the levels: a change between the two is seen
    # twice at worst, and a repeated value is not a change.
    now = time.monotonic()
    for name, path in lines:
        change(name, int(open(path).read().strip()), now, last)
    end_batch()
    event = re.compile(rb"(\d+\.\d+): gpio_value: (\d+) set (\d+)")
    pipe = os.open(TRACE + "/trace_pipe", os.O_RDONLY | os.O_NONBLOCK)
    buf = b""

    def read_events():
        """Every event the kernel holds now; False once there are none."""
        nonlocal buf
        try:
            chunk = os.read(pipe, 65536)
        except BlockingIOError:
            return False
        if not chunk:
            return False
        buf += chunk
        *done, buf = buf.split(b"\n")
        for line in done:
            m = event.search(line)
            if m and int(m.group(2)) in by_gpio:
                change(by_gpio[int(m.group(2))], int(int(m.group(3)) != 0),
                       float(m.group(1)), last)
        end_batch()
        return True

    # SIGTERM only sets a flag: the loop wakes at least every 0.1 s to see
    # it, and then reads what the kernel still holds. A test stops the
    # sampler right after glint exits, when glint's last values (outputs
    # made safe) may not have been read yet; stopping at once lost them.
    while not stopping[0]:
        select.select([pipe], [], [], 0.1)
        while read_events():
            pass
    while read_events():
        pass
    put(EVENT + "/enable", "0")


main()
