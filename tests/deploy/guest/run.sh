#!/bin/sh
# The deployment test, in the booted guest (tests/deploy, docs/deploy.md): the package
# installed, run, faulted, upgraded, disabled, removed and purged as an admin would, with apt
# and systemctl. Every check prints "deploy: ok: WHAT (N s)" or "deploy: FAILED: WHAT" and the
# service's journal; the host test reads them on the console and the firmware's link on the
# UART. Runs from the test's disk (/run/deploy: the packages, a local apt repository of their
# dependencies, the board file), as root, then the guest powers off.
set -u
here=/run/deploy
start=$(cut -d. -f1 /proc/uptime)
export DEBIAN_FRONTEND=noninteractive LC_ALL=C

elapsed() { echo $(($(cut -d. -f1 /proc/uptime) - start)); }
say() { echo "deploy: $*"; }
fail() {
  say "FAILED: $*"
  systemctl status --no-pager epipole.service 2>&1 | head -20
  journalctl --no-pager -o short-monotonic -u epipole.service 2>&1 | tail -40
  exit 1
}
# check WHAT COMMAND...: the command must succeed.
check() {
  what=$1
  shift
  "$@" || fail "$what"
  say "ok: $what ($(elapsed) s)"
}
# Retries the command every half second for at most $1 seconds.
within() {
  seconds=$1
  shift
  tries=$((seconds * 2))
  until "$@"; do
    tries=$((tries - 1))
    [ $tries -le 0 ] && return 1
    sleep 0.5
  done
}
property() { systemctl show -p "$1" --value epipole.service; }
main_pid() { property MainPID; }
is_active() { [ "$(systemctl is-active epipole.service)" = active ]; }
pid_changed_from() { [ "$(main_pid)" != "$1" ] && [ "$(main_pid)" != 0 ] && is_active; }
runs_as_epipole() { [ "$(ps -o user= -p "$(main_pid)")" = epipole ]; }
installed_version() { dpkg-query -W -f='${Version}' epipole 2>/dev/null; }
journal_since() { journalctl --no-pager -o cat -u epipole.service --since "@$1"; }
journal_has() { journal_since "$1" | grep -q "$2"; }
# The watchdog is pinged: the time of its last ping moves on.
watchdog_pinged() {
  first=$(property WatchdogTimestampMonotonic)
  sleep 3
  [ "$first" != 0 ] && [ "$(property WatchdogTimestampMonotonic)" != "$first" ]
}
stays_up() {
  restarts=$(property NRestarts)
  pid=$(main_pid)
  sleep "$1"
  is_active && [ "$(main_pid)" = "$pid" ] && [ "$(property NRestarts)" = "$restarts" ]
}
# apt-get, its output shown only when it fails.
apt() { apt-get -y -q -o Dpkg::Use-Pty=0 "$@" >/tmp/apt.log 2>&1 || { cat /tmp/apt.log; return 1; }; }
restarted() { systemctl restart epipole.service && within 30 is_active; }
stopped() { ! is_active; }
# The gpio-sim chip is the gpio group's; the machine's own PL061 stays root's.
only_the_trigger_chip() {
  for chip in /dev/gpiochip*; do
    driver=$(basename "$(readlink -f "/sys/bus/gpio/devices/${chip#/dev/}/../driver")")
    group=$(stat -c %G "$chip")
    echo "  $chip ($driver): group $group"
    if [ "$driver" = gpio-sim ]; then [ "$group" = gpio ] || return 1; else [ "$group" = root ] || return 1; fi
  done
}
cameras_recovered() { [ "$(journal_since "$1" | grep -c 'camera .* recovered')" -ge 2 ]; }
# The firmware's threads as ps sees them: name, scheduling class, real-time priority.
threads() { ps -L -o comm=,cls=,rtprio= -p "$(main_pid)"; }
# thread_runs NAME CLASS PRIORITY: there is a thread of that name, and each runs so.
thread_runs() {
  threads | awk -v n="$1" -v c="$2" -v p="$3" \
    '$1 == n { seen = 1; if ($2 != c || $3 != p) bad = 1 } END { exit !(seen && !bad) }'
}
# Every thread the firmware starts allowed on CPU 1 only (threads.affinity); the threads
# libraries start before main (libcamera's LTTng listeners, epipole-fw-ust) keep their CPUs.
all_on_cpu1() {
  for task in /proc/"$(main_pid)"/task/*; do
    case $(cat "$task/comm") in
      epipole-fw | epipole-work | epipole-link | epipole-trigger | epipole-snap)
        [ "$(awk '/^Cpus_allowed_list/ { print $2 }' "$task/status")" = 1 ] || return 1 ;;
    esac
  done
}
memory_locked() { [ "$(awk '/^VmLck/ { print $2 }' /proc/"$(main_pid)"/status)" -gt 0 ]; }
# A snapshot the robot asked for (deploy_test.cpp sends one on the link), written by the service
# into its state folder, readable by the epipole group only (UMask=0027).
snapshot_written() {
  file=$(ls /var/lib/epipole/snapshots/snapshot-*-left-raw.pgm 2>/dev/null | head -1)
  [ -n "$file" ] && [ "$(stat -c %U:%G:%a "$file")" = epipole:epipole:640 ] &&
    [ "$(head -c 2 "$file")" = P5 ]
}
# The package as built (no suffix), or as the upgrade the suffix names.
package() { ls "$here"/epipole_*_arm64.deb | grep -e "_[0-9.]*${1}_arm64.deb\$" | head -1; }

say "start: kernel $(uname -r), $(nproc) CPUs, systemd $(systemctl --version | head -1 | cut -d' ' -f2)"

# The board's devices: two vivid cameras and a gpio-sim chip whose line 0 is cam-trigger. The
# link UART (/dev/ttyS0) and the PL011 (/dev/ttyAMA0) are the machine's.
check "cameras loaded" modprobe vivid n_devs=2 node_types=0x1,0x1 num_inputs=1,1 input_types=0x0,0x0
sim=/sys/kernel/config/gpio-sim/deploy
check "trigger line made" sh -c "modprobe gpio-sim && mkdir -p $sim/bank0/line0 &&
  echo 2 >$sim/bank0/num_lines && echo cam-trigger >$sim/bank0/line0/name && echo 1 >$sim/live"
check "devices settled" udevadm settle -t 30
# The trigger's edges follow the left camera's frames, half a period ahead of each (the virtual
# board's driver, docs/vboard.md), from the frame completions the kernel traces.
trace=/sys/kernel/tracing/instances/deploy
check "frames traced" sh -c "{ mountpoint -q /sys/kernel/tracing ||
  mount -t tracefs tracefs /sys/kernel/tracing; } && mkdir -p $trace &&
  echo mono >$trace/trace_clock && echo 1 >$trace/events/vb2/vb2_buf_done/enable &&
  echo 1 >$trace/events/v4l2/v4l2_dqbuf/enable"
trigger_chip=$(cat $sim/bank0/chip_name)
trigger_pull=/sys/devices/platform/$(cat $sim/dev_name)/$trigger_chip/sim_gpio0/pull

# The dependencies come from a local repository (the guest has no network).
echo "deb [trusted=yes] file:$here/repo ./" >/etc/apt/sources.list.d/deploy.list
check "apt sees the local repository" apt update

# 1. A fresh install: the package's own board file (the Raspberry Pi 5's), whose cameras and
# trigger line this board does not have, and no calibration. The service starts, waits for
# them, and does not crash-loop.
v1=$(package "")
[ -n "$v1" ] || fail "no package on the test's disk"
t=$(date +%s)
check "apt install $(basename "$v1")" apt install "$v1"
check "enabled on the first install" [ "$(systemctl is-enabled epipole.service)" = enabled ]
check "active (running) with the package's board file" within 60 is_active
check "runs as the epipole user" runs_as_epipole
check "journal: not calibrated" within 20 journal_has "$t" "not calibrated"
check "journal: waits for the missing cameras" within 20 journal_has "$t" "camera .* lost, reopening"
check "journal: waits for the missing trigger line" within 20 journal_has "$t" "trigger GPIO17 .*waiting"
say "journal says: $(journal_since "$t" | grep -m1 'trigger GPIO17')"
check "no crash loop (10 s, no restart)" stays_up 10
check "watchdog pinged" watchdog_pinged

# 2. The admin's board file and its device rules (which replace the package's: the trigger's
# chip is another one): the firmware streams over the UART, uncalibrated.
cp "$here/board.yaml" /etc/epipole/board.yaml
cp "$here/udev.rules" /etc/udev/rules.d/60-epipole.rules
check "the board's rules applied" sh -c 'udevadm control --reload &&
  udevadm trigger --action=change --subsystem-match=gpio && udevadm settle -t 30'
check "only the trigger's chip for the gpio group" only_the_trigger_chip
taskset -c 0 "$here/vboard-trigger" "/dev/$trigger_chip" 0 "$trigger_pull" "$trace/trace_pipe" 5 /dev/video0 \
  >/tmp/trigger.log 2>&1 &
t=$(date +%s)
check "restarted with the edited board file" restarted
say "streaming"
check "streams for 10 s without a restart" stays_up 10
check "journal: not calibrated" journal_has "$t" "not calibrated"
check "runs as the epipole user" runs_as_epipole
check "watchdog pinged" watchdog_pinged
# The Raspberry Pi 5's scheduling and memory settings, under the unit's sandbox as installed.
say "threads: $(threads | sort | uniq -c | tr -s ' \n' ' ')"
check "frame loop and workers SCHED_FIFO 50" thread_runs epipole-fw FF 50
check "vision worker SCHED_FIFO 50" thread_runs epipole-work FF 50
check "link thread SCHED_FIFO 51" thread_runs epipole-link FF 51
check "trigger thread SCHED_FIFO 52" thread_runs epipole-trigger FF 52
check "snapshot thread at normal scheduling" thread_runs epipole-snap TS -
check "the firmware's threads on CPU 1" all_on_cpu1
check "memory locked" memory_locked
check "snapshot written in the state folder" within 60 snapshot_written

# 3. Killed: systemd starts it again.
pid=$(main_pid)
restarts=$(property NRestarts)
kill -9 "$pid"
check "restarted after kill -9" within 30 pid_changed_from "$pid"
check "counted as a restart" [ "$(property NRestarts)" = $((restarts + 1)) ]

# 4. The cameras go (unbound from their driver, as if unplugged; the module unloaded once the
# firmware has let them go) and come back: the firmware recovers without a restart.
sleep 3
pid=$(main_pid)
t=$(date +%s)
for device in /sys/bus/platform/drivers/vivid/vivid.*; do
  echo "${device##*/}" >/sys/bus/platform/drivers/vivid/unbind
done
check "vivid unloaded once the firmware let the cameras go" within 20 rmmod vivid
check "journal: cameras lost" within 10 journal_has "$t" "camera .* lost, reopening"
check "cameras loaded again" modprobe vivid n_devs=2 node_types=0x1,0x1 num_inputs=1,1 input_types=0x0,0x0
check "journal: cameras recovered" within 30 cameras_recovered "$t"
check "recovered without a restart" [ "$(main_pid)" = "$pid" ]
say "streaming again"
sleep 5

# 5. An upgrade keeps the edited board file and restarts the service.
v2=$(package "+upgrade1")
pid=$(main_pid)
check "apt install $(basename "$v2") (upgrade)" apt install "$v2"
check "upgraded" [ "$(installed_version)" = "$(dpkg-deb -f "$v2" Version)" ]
check "the edited board file kept" cmp -s "$here/board.yaml" /etc/epipole/board.yaml
check "restarted by the upgrade" within 30 pid_changed_from "$pid"
check "still enabled" [ "$(systemctl is-enabled epipole.service)" = enabled ]

# 6. The admin disables it: the next upgrade keeps it disabled.
check "systemctl disable" systemctl disable --quiet epipole.service
v3=$(package "+upgrade2")
check "apt install $(basename "$v3") (upgrade)" apt install "$v3"
check "upgraded" [ "$(installed_version)" = "$(dpkg-deb -f "$v3" Version)" ]
check "still disabled" [ "$(systemctl is-enabled epipole.service)" = disabled ]

# 7. Removed: stopped, the conffile kept; purged: nothing of the package is left.
check "apt remove" apt remove epipole
check "stopped" stopped
check "the unit's file gone" [ ! -e /usr/lib/systemd/system/epipole.service ]
check "the board file kept (a conffile)" [ -f /etc/epipole/board.yaml ]
check "apt purge" apt purge epipole
leftovers() {
  dpkg-query -W epipole >/dev/null 2>&1 && echo "dpkg still knows epipole"
  getent passwd epipole
  # (the test's own runner is epipole-deploy-test.service; the admin's rules are the admin's)
  find /etc /var/lib /usr /run/systemd/system /run/udev/rules.d -name '*epipole*' \
    -not -name 'epipole-deploy-test*' -not -path /etc/udev/rules.d/60-epipole.rules 2>/dev/null
  systemctl list-unit-files --no-legend epipole.service 2>/dev/null
}
nothing_left() { [ -z "$(leftovers)" ] || { leftovers; false; }; }
check "purged: nothing of the package left" nothing_left
say "all passed ($(elapsed) s)"
