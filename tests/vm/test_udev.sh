#!/bin/bash
# glint's udev rule (scripts/udev/70-glint.rules) in the test VM: with the
# rule in udev's runtime rules folder and a glint-dev group, the camera
# (vivid) and a GPIO chip (gpio-sim) become usable by a user whose only
# group is glint-dev, and by no other: not by the queue's glint group;
# Debian's owners and groups stay.
# usage: test_udev.sh RULES_FILE   (inside scripts/vm run)
set -u
here=$(dirname "$0")
. "$here/../wait.sh"
. "$here/lib.sh"
rules=$1
in_vm || {
	echo "skip: needs the test VM (scripts/vm run)" >&2
	exit 77
}
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
cp "$rules" /run/udev/rules.d/

check "vivid loads" load_module vivid
check "... its video node appears" wait_until 10 exists "/dev/video*"
chip=$(gpio_sim_chip udev glint-rig 4 0=glint-button)
check "a gpio-sim chip ($chip)" test -c "/dev/$chip"
video=$(ls /dev/video* | head -1)
/lib/systemd/systemd-udevd >/dev/null 2>&1 &
udevd=$!
check "udev has run the rule" udev_ready "$video" "/dev/$chip"

has_acl() { getfacl -p "$1" 2>/dev/null | grep -q "^group:glint-dev:rw-$"; }
check "the video node grants the glint-dev group rw" has_acl "$video"
check "the GPIO chip grants the glint-dev group rw" has_acl "/dev/$chip"
for m in /dev/media*; do
	[ -e "$m" ] && check "$m grants the glint-dev group rw" has_acl "$m"
done
# Debian's own rules still apply: the camera's group stays video; the
# GPIO chip stays root's (its owning group gets nothing from the ACL).
check "the camera keeps Debian's video group" test "$(stat -c %U:%G "$video")" = root:video
check "the GPIO chip keeps its owner and group, and the group no access" \
	bash -c "test \"\$(stat -c %U:%G /dev/$chip)\" = root:root && getfacl -p /dev/$chip | grep -q '^group::---$'"

as() { # GID COMMAND...: as an unprivileged user whose only group is GID
	local g=$1
	shift
	setpriv --reuid=4243 --regid="$g" --clear-groups "$@"
}
check "a glint-dev user opens the GPIO chip" as "$gid" gpioinfo "$chip"
check "... and queries the camera" as "$gid" v4l2-ctl -d "$video" --info
check "a user of the queue's glint group cannot open the GPIO chip" bash -c "! setpriv --reuid=4243 --regid=$qgid --clear-groups gpioinfo $chip >/dev/null 2>&1"
check "... nor the camera" bash -c "! setpriv --reuid=4243 --regid=$qgid --clear-groups v4l2-ctl -d $video --info >/dev/null 2>&1"
check "a user of another group cannot open the GPIO chip" bash -c "! setpriv --reuid=4243 --regid=4244 --clear-groups gpioinfo $chip >/dev/null 2>&1"
check "... nor the camera" bash -c "! setpriv --reuid=4243 --regid=4244 --clear-groups v4l2-ctl -d $video --info >/dev/null 2>&1"
finish
