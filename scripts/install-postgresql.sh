#!/bin/sh
# PostgreSQL (the server the incident store's tests start in a temporary directory on a loopback
# port). Debian's package, installed where missing; nothing is done if it is already there.
set -e
if ls /usr/lib/postgresql/*/bin/initdb >/dev/null 2>&1 || command -v initdb >/dev/null 2>&1; then
    exit 0
fi
if [ "$(id -u)" = "0" ] && command -v apt-get >/dev/null 2>&1; then
    # Wait for a dpkg lock held by another apt rather than fail; refresh the package lists once
    # if the package is not found in them. The cluster Debian's package creates and starts is
    # not used by the tests (they start their own).
    apt="apt-get -o DPkg::Lock::Timeout=600"
    $apt install -y postgresql || { $apt update && $apt install -y postgresql; }
    exit 0
fi
echo "PostgreSQL is not installed: install Debian's package ('sudo apt-get install postgresql')" >&2
echo "or your system's equivalent; the incident store's tests need its initdb and pg_ctl." >&2
exit 1
