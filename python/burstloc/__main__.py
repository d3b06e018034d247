"""``python -m burstloc``: the same as the ``burstloc`` command."""

from burstloc.cli import run

run()
