#!/bin/sh
# Chromium and its WebDriver (the browser the control-room page's tests drive, through Selenium).
# Installed where missing; nothing is done if both are already there. Only the tests need them
# (`make test`), not `make paper` or `burstloc monitor --web`.
set -e
have() { command -v "$1" >/dev/null 2>&1; }
if { have chromium || have chromium-browser; } && { have chromedriver || [ -x /usr/lib/chromium/chromedriver ]; }; then
    exit 0
fi
if [ "$(id -u)" = "0" ] && command -v apt-get >/dev/null 2>&1; then
    # Wait for a dpkg lock held by another apt rather than fail; refresh the package lists once
    # if the packages are not found in them.
    apt="apt-get -o DPkg::Lock::Timeout=600"
    $apt install -y chromium chromium-driver || { $apt update && $apt install -y chromium chromium-driver; }
    exit 0
fi
echo "Chromium is not installed: install Debian's packages ('sudo apt-get install chromium" >&2
echo "chromium-driver') or your system's equivalent; the control-room page's tests need them." >&2
exit 1
