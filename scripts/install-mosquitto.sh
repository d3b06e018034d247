#!/bin/sh
# Mosquitto (the MQTT broker the monitor's integration tests start on a loopback port).
# Installed where missing; nothing is done if it is already there.
set -e
if command -v mosquitto >/dev/null 2>&1 || [ -x /usr/sbin/mosquitto ]; then
    exit 0
fi
if [ "$(id -u)" = "0" ] && command -v apt-get >/dev/null 2>&1; then
    apt-get install -y mosquitto
    exit 0
fi
echo "mosquitto is not installed: install Debian's package ('sudo apt-get install mosquitto')" >&2
echo "or your system's equivalent; the MQTT tests of burstloc monitor need it." >&2
exit 1
