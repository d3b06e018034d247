#!/bin/sh
# Mosquitto (the MQTT broker the monitor's integration tests start on a loopback port).
# Installed where missing; nothing is done if it is already there.
set -e
if command -v mosquitto >/dev/null 2>&1 || [ -x /usr/sbin/mosquitto ]; then
    exit 0
fi
if [ "$(id -u)" = "0" ] && command -v apt-get >/dev/null 2>&1; then
    # Wait for a dpkg lock held by another apt (unattended upgrades, a parallel setup) rather than
    # fail; refresh the package lists once if the package is not found in them.
    apt="apt-get -o DPkg::Lock::Timeout=600"
    $apt install -y mosquitto || { $apt update && $apt install -y mosquitto; }
    exit 0
fi
echo "mosquitto is not installed: install Debian's package ('sudo apt-get install mosquitto')" >&2
echo "or your system's equivalent; the MQTT tests of burstloc monitor need it." >&2
exit 1
