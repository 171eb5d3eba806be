#!/bin/bash
# The job queue shared by two real accounts, in the test VM: alice and bob
# (in passwd and group files bind-mounted over the host's read-only ones),
# both in the queue's glint group, on a captures root made as the service
# makes it (root:glint, setgid, on a tmpfs: the kernel's own permission
# rules, not a shared folder's).  Each user queues his own sessions; the
# other cannot cancel, move or delete the job, nor queue a session not
# shared with him; a worker running as root runs each job as its
# submitter, with the submitter's groups from the group file, and the
# fit's files are his.
# usage: users.sh GLINT RUN   (inside scripts/vm run, as root; RUN a rig
# run's folder: a probe and a sample session, as the press made them)
set -u
here=$(dirname "$0")
. "$here/../wait.sh"
. "$here/lib.sh"
glint=$1 run=$2
need_vm
base=$(mktemp -d /run/glint-users.XXXXXX)
trap 'umount "$base" /etc/group /etc/passwd 2>/dev/null; rmdir "$base"' EXIT
mount -t tmpfs -o mode=0755 tmpfs "$base" || exit 1

cp /etc/passwd "$base/passwd"
cp /etc/group "$base/group"
cat >>"$base/passwd" <<'EOF'
alice:x:4246:4246:Alice:/nonexistent:/bin/sh
bob:x:4247:4247:Bob:/nonexistent:/bin/sh
EOF
sed -i '/^glint:/d' "$base/group"
cat >>"$base/group" <<'EOF'
alice:x:4246:
bob:x:4247:
glint:x:4245:alice,bob
EOF
mount --bind "$base/passwd" /etc/passwd && mount --bind "$base/group" /etc/group || exit 1
as() { # USER COMMAND...: as that account, with its groups
	local u=$1
	shift
	setpriv --reuid="$u" --regid="$u" --init-groups "$@"
}
check "two accounts, alice and bob, in the glint group" \
	bash -c "id -nG alice | grep -qw glint && id -nG bob | grep -qw glint"

# The captures root as the unit makes it (StateDirectoryMode=2770,
# UMask=0007); the queue made by its worker.
umask 0007
lab=$base/captures
mkdir "$lab" && chown root:glint "$lab" && chmod 2770 "$lab"
"$glint" queue run --until-empty --root "$lab" -q
q=$lab/queue
# Each one's copy of the run, his own.
for u in alice bob; do
	cp -a "$run" "$lab/$u-run"
	rm -rf "$lab/$u-run"/sample-*/fit "$lab/$u-run"/sample-*/fit.lock
	chown -R "$u:$u" "$lab/$u-run"
done
asess=$(ls -d "$lab"/alice-run/sample-*)
bsess=$(ls -d "$lab"/bob-run/sample-*)

id=$(as alice "$glint" queue add "$asess" --root "$lab")
check "alice queues her session" test -n "$id" -a -f "$q/pending/$id.json"
check "... bob's glint jobs names her as its submitter" \
	bash -c "setpriv --reuid=bob --regid=bob --init-groups '$glint' jobs --root '$lab' | grep -q '^$id  *pending  *fit  *alice '"
check "... bob cannot cancel it (the submitter named)" \
	bash -c "! setpriv --reuid=bob --regid=bob --init-groups '$glint' queue cancel '$id' --root '$lab' 2>'$base/err' && grep -q 'submitted by uid 4246' '$base/err'"
check "... nor move or delete its file (sticky state folders)" \
	bash -c "! setpriv --reuid=bob --regid=bob --init-groups mv '$q/pending/$id.json' '$q/cancelled/' 2>/dev/null && ! setpriv --reuid=bob --regid=bob --init-groups rm -f '$q/pending/$id.json' 2>/dev/null && test -f '$q/pending/$id.json'"
check "bob cannot queue alice's session (not shared with him)" \
	bash -c "! setpriv --reuid=bob --regid=bob --init-groups '$glint' queue add '$asess' --root '$lab' 2>'$base/err' && grep -q 'not shared with the job.s submitter (uid 4247)' '$base/err'"

# The worker, as root: alice's job runs as alice.
"$glint" queue run --until-empty --root "$lab" 2>"$base/werr"
check "the root worker runs alice's job as alice" grep -q "job $id: fitting .* as uid 4246" "$base/werr"
check "... it is done, and its fit's files are hers" \
	bash -c "'$glint' jobs --root '$lab' | grep -q '^$id  *done ' && test \"\$(stat -c %U '$asess/fit/params.json')\" = alice" ||
	{ cat "$base/werr"; "$glint" jobs --root "$lab"; }

# Bob shares his session with the group; its photo is readable by the
# group alone and damaged.  Alice may queue it, and the worker's fit, as
# alice with her groups from the group file, reads the photo and finds
# the damage (as alice without them it would be refused the file).
chgrp -R glint "$lab/bob-run" && chmod -R g+w "$lab/bob-run"
chmod 0640 "$bsess/sample.exr" && chown bob:glint "$bsess/sample.exr"
truncate -s 2000 "$bsess/sample.exr"
id2=$(as alice "$glint" queue add "$bsess" --root "$lab")
check "alice queues bob's session shared with the group" test -n "$id2"
"$glint" queue run --until-empty --root "$lab" 2>>"$base/werr"
"$glint" jobs --root "$lab" --json >"$base/jobs.json"
check "... her job runs with her groups: the photo read, its damage named" python3 - "$base/jobs.json" "$id2" <<'PY'
import json, sys
jobs = {j["id"]: j for j in json.load(open(sys.argv[1]))["jobs"]}
j = jobs[sys.argv[2]]
err = j.get("error", "")
print("  ", j["state"], err)
assert j["state"] == "failed" and "sample.exr" in err and "ermission" not in err
PY
finish
