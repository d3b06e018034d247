#!/usr/bin/env bash
# A plain pip install, as a user without the Makefile makes one, then the README's tour as written.
#
#   scripts/smoke-pip.sh PYTHON WHEEL
#
# A fresh virtualenv on PYTHON (no Makefile venv, no cache), `pip install 'WHEEL[sim]'`, then the
# shell block of README.md after the line `<!-- tour -->`, run in an empty directory holding only
# networks/paper15.inp, with an empty simulation cache. Fails if any command fails or if the
# monitor does not name the burst pipe of the tour (P7). Everything is removed afterwards.
set -euo pipefail
python=$1
wheel=$2
root=$(pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

"$python" -m venv "$work/venv"
"$work/venv/bin/python" -m pip install -q "$wheel[sim]"
"$work/venv/bin/python" -c 'import sys; print("plain pip install on Python", sys.version.split()[0])'

sed -n '/^<!-- tour -->$/,/^```$/p' "$root/README.md" | sed '1,2d;$d' > "$work/tour.sh"
test -s "$work/tour.sh" || { echo "smoke-pip: no tour block in README.md" >&2; exit 1; }
mkdir -p "$work/run/networks"
cp "$root/networks/paper15.inp" "$work/run/networks/"
cd "$work/run"
PATH="$work/venv/bin:$PATH" BURSTLOC_CACHE_DIR="$work/cache" bash -ex "$work/tour.sh" | tee "$work/out"
grep -q '"type": "decision".*"pipes": \[{"pipe": "P7"' "$work/out" \
    || { echo "smoke-pip: the monitor did not name pipe P7" >&2; exit 1; }
echo "smoke-pip: the README's tour ran as written; the monitor named pipe P7"
