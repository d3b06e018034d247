"""``python -m burstloc.cli``: the same as the ``burstloc`` command."""

from burstloc.cli import main

raise SystemExit(main())
