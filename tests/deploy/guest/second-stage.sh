#!/bin/sh
# The board's set-up, run once in the new root filesystem after debootstrap's second stage
# (tests/deploy/guest/init): no logins on the consoles, the test's runner enabled, the
# journal kept small.
set -e
passwd -d root >/dev/null
# The console is the test's; the PL011 is the board file's UART: no getty on either.
systemctl mask serial-getty@hvc0.service serial-getty@ttyAMA0.service getty@tty1.service \
  >/dev/null 2>&1
systemctl mask apt-daily.timer apt-daily-upgrade.timer e2scrub_all.timer fstrim.timer \
  >/dev/null 2>&1 || true
systemctl enable epipole-deploy-test.service >/dev/null 2>&1
mkdir -p /etc/systemd/journald.conf.d
printf '[Journal]\nStorage=volatile\nRuntimeMaxUse=16M\n' >/etc/systemd/journald.conf.d/deploy.conf
apt-get clean
