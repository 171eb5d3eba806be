#!/usr/bin/env python3
"""Read gpio-sim output lines back from the kernel while glint drives them.

usage: sample_lines.py [--world PATH STEPS_PER_TURN] LOG NAME=SYSFS_VALUE_FILE...

Polls each line's sysfs `value` (what the chip's driver holds: the physical
level) as fast as it can and writes every change as a JSON line
{"t": monotonic seconds, "line": NAME, "value": 0|1} to LOG, the first
reading of each line included. Runs until SIGTERM; the log is flushed on
every change so a reader sees it while it runs.

With --world, it also plays the rig's hardware for the simulated camera:
the lamps follow the `lights` line and the turntable turns 360/STEPS_PER_TURN
degrees at each rising edge of `step` (positive with `dir` high), and PATH
says "LIGHTS DEGREES" (the sim camera's world=PATH), replaced whole at each
change.
"""
import json
import os
import signal
import sys
import time

stop = False


def on_term(*_):
    global stop
    stop = True


def main():
    signal.signal(signal.SIGTERM, on_term)
    args = sys.argv[1:]
    world = None
    if args[0] == "--world":
        world, per_turn = args[1], int(args[2])
        args = args[3:]
    log = open(args[0], "w")
    state = {"lights": 0, "deg": 0.0, "dir": 0, "step": 0}

    def write_world():
        tmp = world + ".tmp"
        with open(tmp, "w") as f:
            f.write("%d %.6f\n" % (state["lights"], state["deg"]))
        os.replace(tmp, world)

    if world:
        write_world()
    lines = []
    for arg in args[1:]:  # in order: list dir before step
        name, path = arg.split("=", 1)
        lines.append((name, os.open(path, os.O_RDONLY), [None]))
    while not stop:
        for name, fd, last in lines:
            v = int(os.pread(fd, 8, 0).strip())
            if v != last[0]:
                prev, last[0] = last[0], v
                log.write(json.dumps({"t": time.monotonic(), "line": name, "value": v}) + "\n")
                log.flush()
                if world and name in state:
                    if name == "step" and v == 1 and prev is not None:
                        state["deg"] += (360.0 if state["dir"] else -360.0) / per_turn
                    state[name] = v
                    write_world()
        time.sleep(0.0005)


main()
