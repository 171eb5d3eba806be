# Shared by the tests that run inside the test VM (scripts/vm run): checks
# counted as in the other shell tests, and the kernel's virtual devices
# loaded and configured.  Source it after tests/wait.sh.

fails=0 checks=0
check() { # WHAT COMMAND...: run COMMAND, count it, say ok or FAIL
	local what=$1
	shift
	checks=$((checks + 1))
	if "$@"; then
		echo "ok   $what (at ${SECONDS} s)"
	else
		echo "FAIL $what (at ${SECONDS} s)"
		fails=$((fails + 1))
	fi
}

finish() {
	echo "$((checks - fails)) of $checks checks passed"
	[ "$fails" = 0 ]
}

# udev_has DEV: udevd has processed the device node DEV (its database
# entry exists, as libcamera and the ACL rules need).
udev_has() {
	local t
	t=$(stat -c '%t:%T' "$1" 2>/dev/null) || return 1
	test -e "/run/udev/data/c$((16#${t%%:*})):$((16#${t##*:}))"
}

# udev_ready DEV...: once udevd answers, trigger the devices of the rules'
# subsystems and wait for
# those given (deadlines scaled to the VM's measured speed: under TCG a
# trigger of the whole VM takes tens of seconds); then let the rest settle.
udev_ready() {
	# A trigger before udevd listens is lost: wait until it answers.
	wait_until 30 udevadm control --ping --timeout=1 || return 1
	# Only the subsystems the rules are for: a trigger of every device
	# takes minutes under TCG.
	udevadm trigger --action=add --subsystem-match=video4linux \
		--subsystem-match=media --subsystem-match=gpio \
		--subsystem-match=dma_heap || return 1
	local d
	for d in "$@"; do
		wait_until 60 udev_has "$d" || return 1
	done
	udevadm settle -t "$(scaled 60)"
}

in_vm() { # the modules scripts/vm built are only there inside its VM
	[ -n "${GLINT_VM_MODULES:-}" ] && [ -d "$GLINT_VM_MODULES" ]
}

need_vm() { # outside the VM: meson's skip (77), saying why
	in_vm || {
		echo "skip: needs the test VM (scripts/vm run)" >&2
		exit 77
	}
}

# load_module NAME: a module from Debian's kernel, or one scripts/vm built
# (with the Debian modules it depends on).
load_module() {
	local ko=$GLINT_VM_MODULES/$1.ko
	if [ -f "$ko" ]; then
		local deps
		deps=$(modinfo -F depends "$ko" | tr , ' ')
		[ -z "$deps" ] || modprobe -a $deps || return 1
		grep -q "^${1//-/_} " /proc/modules || insmod "$ko"
	else
		modprobe "$1"
	fi
}

# gpio_sim_chip NAME LABEL NUM_LINES [OFFSET=LINE_NAME...]: a live gpio-sim
# chip; prints its gpiochipN.
gpio_sim_chip() {
	local name=$1 label=$2 n=$3
	shift 3
	load_module configfs || return 1
	grep -qs ' /sys/kernel/config ' /proc/mounts ||
		mount -t configfs none /sys/kernel/config || return 1
	load_module gpio-sim || return 1
	local dev=/sys/kernel/config/gpio-sim/$name
	mkdir "$dev" "$dev/bank0" || return 1
	echo "$label" >"$dev/bank0/label"
	echo "$n" >"$dev/bank0/num_lines"
	local kv
	for kv in "$@"; do
		mkdir "$dev/bank0/line${kv%%=*}"
		echo "${kv#*=}" >"$dev/bank0/line${kv%%=*}/name"
	done
	echo 1 >"$dev/live" || return 1
	cat "$dev/bank0/chip_name"
}

# gpio_sim_dir NAME: the sysfs directory of its chip's sim_gpioN attributes
gpio_sim_dir() {
	local dev=/sys/kernel/config/gpio-sim/$1
	echo "/sys/devices/platform/$(cat "$dev/dev_name")/$(cat "$dev/bank0/chip_name")"
}

# vivid_node: vivid's (first instance's) video capture node, not a real
# camera's.
vivid_node() {
	local d
	for d in /sys/class/video4linux/video*; do
		grep -qs '^vivid-000-vid-cap$' "$d/name" && echo "/dev/${d##*/}" && return 0
	done
	return 1
}
