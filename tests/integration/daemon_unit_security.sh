#!/bin/sh
# The hardened findmugd.service: its systemd-analyze exposure must not rise
# above THRESHOLD (tenths: 12 = 1.2), and the hardening must still admit what
# the daemon needs (checked on the unit text, since no systemd runs as PID 1
# here): the USB camera device nodes, udpm multicast and localhost, the socket
# families of LCM, sd_notify and libusb hot-plug.
# usage: daemon_unit_security.sh SYSTEMD_ANALYZE UNIT_FILE THRESHOLD
set -eu
analyze=$1 unit=$2 threshold=$3
fail() { echo "daemon_unit_security: $*" >&2; exit 1; }

out=$("$analyze" security --offline=true --threshold="$threshold" "$unit" 2>&1) ||
  { echo "$out" | grep -v '✓'; fail "exposure above $threshold/10"; }
echo "$out" | grep 'Overall exposure'

setting() { sed -n "s/^$1=//p" "$unit"; }
# Camera: OpenNI2 opens /dev/bus/usb/BBB/DDD through libusb; those nodes are the
# "usb_device" character devices (major 189 on Linux).
setting DevicePolicy | grep -qx closed || fail "DevicePolicy is not closed"
setting DeviceAllow | grep -q '^char-usb_device rw' || fail "DeviceAllow lacks char-usb_device rw"
# (A machine without USB, like a CI VM, has no usb_device major: nothing to compare.)
if grep -Eq ' usb_device$' /proc/devices 2>/dev/null; then
  grep -Eq '^ *189 usb_device$' /proc/devices || fail "usb_device is not char major 189 here"
else
  echo "no usb_device char devices on this machine: node majors not checked"
fi
for node in /dev/bus/usb/*/*; do
  [ -c "$node" ] || continue
  major=$(stat -c '%t' "$node")
  [ "$major" = bd ] || fail "$node has major 0x$major, not usb_device (0xbd)"
done
# PrivateDevices would hide /dev/bus/usb entirely.
! setting PrivateDevices | grep -qix yes || fail "PrivateDevices=yes hides the camera"
setting SupplementaryGroups | grep -qw plugdev || fail "plugdev (USB camera nodes) missing"

# LCM udpm: multicast group 239.255.76.67 (default) and localhost must be allowed.
allow=$(setting IPAddressAllow)
echo "$allow" | grep -qw multicast || fail "IPAddressAllow lacks multicast (LCM udpm)"
echo "$allow" | grep -qw localhost || fail "IPAddressAllow lacks localhost"
setting IPAddressDeny | grep -qx any || fail "IPAddressDeny is not 'any'"
families=$(setting RestrictAddressFamilies)
for f in AF_INET AF_UNIX AF_NETLINK; do
  echo "$families" | grep -qw "$f" || fail "RestrictAddressFamilies lacks $f"
done
! setting PrivateNetwork | grep -qix yes || fail "PrivateNetwork=yes cuts LCM off"
# sd_notify and the watchdog need the notify socket.
setting Type | grep -qx notify || fail "Type is not notify"
echo "daemon_unit_security: OK"
