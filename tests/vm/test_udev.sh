#!/bin/bash
# The udev rules glint check-rig --udev-rules writes for one rig, in the
# test VM: of two cameras (vivid, vimc) and two gpio-sim chips, the rig
# file names one of each; with the rules in udev's runtime folder and a glint-dev
# group, the rig's camera nodes (video and media, of its parent device)
# and its GPIO chip become usable by a user whose only group is glint-dev,
# the other camera and chip by no one new; not by the queue's glint group
# either; Debian's owners and groups stay.  A libcamera rig naming vimc's
# camera gets rules for vimc.0 and the DMA heaps.  The rules file follows
# glint's overwrite rule, and the simulated rig gets no rules.
# usage: test_udev.sh GLINT DATA_DIR   (inside scripts/vm run)
set -u
here=$(dirname "$0")
. "$here/../wait.sh"
. "$here/lib.sh"
glint=$1 data=$2
need_vm
tmp=$(mktemp -d)
udevd=""
trap '[ -z "$udevd" ] || kill $udevd 2>/dev/null; umount /etc/group 2>/dev/null; rm -rf "$tmp"' EXIT

# The host's /etc is read-only here: the glint-dev (devices, gid 4242) and
# glint (queue, gid 4245) groups over it.
cp /etc/group "$tmp/group"
grep -q '^glint-dev:' "$tmp/group" || echo "glint-dev:x:4242:" >>"$tmp/group"
grep -q '^glint:' "$tmp/group" || echo "glint:x:4245:" >>"$tmp/group"
gid=$(awk -F: '$1 == "glint-dev" {print $3}' "$tmp/group")
qgid=$(awk -F: '$1 == "glint" {print $3}' "$tmp/group")
mount --bind "$tmp/group" /etc/group
mkdir -p /run/udev/rules.d

check "vivid loads (the rig's camera)" modprobe vivid n_devs=1
check "vimc loads (another camera)" load_module vimc
check "... vivid's capture node appears" wait_until 10 vivid_node
cam=$(vivid_node)
# nodes_of PARENT: the video4linux and media nodes of that device.  One
# readlink for all of them: under TCG each process costs a good part of a
# second, and a process or two per node took 40 s.
nodes_of() {
	local d i names=() links=() real=()
	for d in /sys/class/video4linux/*; do
		[ -e "$d/device" ] && names+=("${d##*/}") links+=("$d/device")
	done
	# a media controller is a bus device: its folder lies in its parent's
	for d in /sys/bus/media/devices/*; do
		[ -e "$d" ] && names+=("${d##*/}") links+=("$d/..")
	done
	((${#links[@]})) || return 0
	# (a here-string: the VM has no /dev/fd for a process substitution)
	mapfile -t real <<<"$(readlink -f "${links[@]}")"
	for i in "${!names[@]}"; do
		[ "${real[i]##*/}" = "$1" ] && echo "/dev/${names[i]}"
	done
	return 0
}
has_nodes() { [ -n "$(nodes_of "$1")" ]; }
check "... vimc's nodes appear" wait_until 10 has_nodes vimc.0
mine=$(nodes_of vivid.0) theirs=$(nodes_of vimc.0)
other=$(for n in $theirs; do case $n in /dev/video*) echo "$n"; break ;; esac; done)
check "the rig's camera $cam is vivid.0's; vimc.0 has nodes of its own ($other ...)" \
	bash -c "grep -qx '$cam' <<<'$mine' && test -n '$other'"
chip=$(gpio_sim_chip rig glint-rig 32 17=glint-button 22=glint-lights 27=glint-led 23=glint-step 24=glint-dir 25=glint-enable)
chip2=$(gpio_sim_chip spare other-board 8)
check "two gpio-sim chips ($chip, $chip2)" test -c "/dev/$chip" -a -c "/dev/$chip2"
chip_parent=$(basename "$(dirname "$(readlink -f /sys/bus/gpio/devices/$chip)")")
chip2_parent=$(basename "$(dirname "$(readlink -f /sys/bus/gpio/devices/$chip2)")")
check "... of two devices ($chip_parent, $chip2_parent)" test "$chip_parent" != "$chip2_parent"

# The rig file: vivid.0's capture node, every line on the chip labelled
# glint-rig, by name.
python3 - "$data/rig-sim.json" "$tmp/rig.json" "$cam" "$tmp/out" <<'PY'
import json, sys
src, dst, cam, out = sys.argv[1:]
r = json.load(open(src))
r["output"] = out
r["camera"] = {"backend": "v4l2", "device": cam}
b = r["board"]
b["backend"] = "gpiod"
b.pop("scenario", None)
names = {"button": "glint-button", "lights": "glint-lights", "led": "glint-led",
         "turntable_step": "glint-step", "turntable_dir": "glint-dir",
         "turntable_enable": "glint-enable"}
for role, name in names.items():
    b["lines"][role].update(chip="glint-rig", line=name)
    b["lines"][role].pop("offset", None)
json.dump(r, open(dst, "w"), indent=1)
PY
rules=/run/udev/rules.d/70-glint.rules
check "check-rig --udev-rules writes the rig's rules" \
	"$glint" check-rig --config "$tmp/rig.json" --udev-rules "$rules" -q
cat "$rules"
check "... matching the camera's and the chip's parent devices" \
	bash -c "grep -q 'KERNELS==\"vivid.0\"' '$rules' && grep -q 'KERNELS==\"$chip_parent\"' '$rules' && ! grep -q 'vimc\|$chip2_parent\|dma_heap' '$rules'"
check "... an existing rules file refused without --force" \
	bash -c "! '$glint' check-rig --config '$tmp/rig.json' --udev-rules '$rules' -q 2>'$tmp/err' && grep -q 'exists' '$tmp/err'"
check "... replaced with --force (glint wrote it)" \
	"$glint" check-rig --config "$tmp/rig.json" --udev-rules "$rules" --force -q
echo "# a rule of the admin's" >"$tmp/admin.rules"
check "... another's file refused even with --force" \
	bash -c "! '$glint' check-rig --config '$tmp/rig.json' --udev-rules '$tmp/admin.rules' --force -q 2>/dev/null && grep -q admin '$tmp/admin.rules'"
check "the simulated rig: no rules, said why" \
	bash -c "! '$glint' check-rig --config '$data/rig-sim.json' --udev-rules - 2>'$tmp/err' && grep -q 'use no device' '$tmp/err'"

/lib/systemd/systemd-udevd >/dev/null 2>&1 &
udevd=$!
check "udev has run the rules" udev_ready $mine $theirs "/dev/$chip" "/dev/$chip2"

has_acl() { getfacl -p "$1" 2>/dev/null | grep -q "^group:glint-dev:rw-$"; }
for n in $mine; do
	check "$n (vivid.0) grants the glint-dev group rw" has_acl "$n"
done
for n in $theirs; do
	check "$n (vimc.0) grants it nothing" bash -c "! getfacl -p $n 2>/dev/null | grep -q glint-dev"
done
check "the rig's GPIO chip grants the glint-dev group rw" has_acl "/dev/$chip"
check "the other chip grants it nothing" bash -c "! getfacl -p /dev/$chip2 2>/dev/null | grep -q glint-dev"
# Debian's own rules still apply: the camera's group stays video; the
# GPIO chip stays root's (its owning group gets nothing from the ACL).
check "the camera keeps Debian's video group" test "$(stat -c %U:%G "$cam")" = root:video
check "the GPIO chip keeps its owner and group, and the group no access" \
	bash -c "test \"\$(stat -c %U:%G /dev/$chip)\" = root:root && getfacl -p /dev/$chip | grep -q '^group::---$'"

as() { # GID COMMAND...: as an unprivileged user whose only group is GID
	local g=$1
	shift
	setpriv --reuid=4243 --regid="$g" --clear-groups "$@"
}
check "a glint-dev user opens the rig's GPIO chip" as "$gid" gpioinfo "$chip"
check "... and queries the rig's camera" as "$gid" v4l2-ctl -d "$cam" --info
check "... but not the other chip" bash -c "! setpriv --reuid=4243 --regid=$gid --clear-groups gpioinfo $chip2 >/dev/null 2>&1"
check "... nor the other camera" bash -c "! setpriv --reuid=4243 --regid=$gid --clear-groups v4l2-ctl -d $other --info >/dev/null 2>&1"
check "a user of the queue's glint group cannot open the GPIO chip" bash -c "! setpriv --reuid=4243 --regid=$qgid --clear-groups gpioinfo $chip >/dev/null 2>&1"
check "... nor the camera" bash -c "! setpriv --reuid=4243 --regid=$qgid --clear-groups v4l2-ctl -d $cam --info >/dev/null 2>&1"
# The rules for a libcamera camera (vimc's, by its id): its media
# device's parent and the DMA heaps; none of vivid's nodes.
export LIBCAMERA_LOG_LEVELS='*:ERROR'
lcid=$("$glint" cameras --backend libcamera --json 2>/dev/null |
	python3 -c "import json, sys; print(json.load(sys.stdin)['cameras'][0]['device'])")
python3 - "$data/rig-sim.json" "$tmp/rig-lc.json" "$lcid" "$tmp/out" <<'PY'
import json, sys
src, dst, cam, out = sys.argv[1:]
r = json.load(open(src))
r["output"] = out
r["camera"] = {"backend": "libcamera", "device": cam}
r.pop("board", None)
r.pop("sequence", None)
json.dump(r, open(dst, "w"), indent=1)
PY
check "a libcamera rig ($lcid): rules for vimc.0's nodes and the DMA heaps" \
	bash -c "'$glint' check-rig --config '$tmp/rig-lc.json' --udev-rules - >'$tmp/lc.rules' 2>'$tmp/err' && grep -q 'KERNELS==\"vimc.0\"' '$tmp/lc.rules' && grep -q 'dma_heap' '$tmp/lc.rules' && ! grep -q 'vivid\|gpio' '$tmp/lc.rules' || { cat '$tmp/err' '$tmp/lc.rules'; false; }"
check "a user of another group cannot open the GPIO chip" bash -c "! setpriv --reuid=4243 --regid=4244 --clear-groups gpioinfo $chip >/dev/null 2>&1"
check "... nor the camera" bash -c "! setpriv --reuid=4243 --regid=4244 --clear-groups v4l2-ctl -d $cam --info >/dev/null 2>&1"
finish
