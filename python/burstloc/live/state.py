"""The monitor's saved state: one JSON file, written atomically, versioned, bound to its setup.

A state file (format :data:`STATE_FORMAT`) holds the live loop's whole state (detector bank
snapshot, history ring, pending decision, hold-off, stream assembly, meter health) and the
*identity* of the setup that wrote it: the network's SHA-256, the configuration's name and
digest, the meters, the capture interval, the detector, localizer and meter model.
:meth:`StateFile.load` refuses, naming the difference, a state written for another setup or by
another format version. Files are written with :func:`burstloc._atomic.write_json`: a reader
(or a restart after ``kill -9``) sees the previous state or the new one, never a partial file.
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from burstloc._atomic import write_json
from burstloc.exceptions import ConfigError
from burstloc.localize.config import Calibration

__all__ = ["STATE_FORMAT", "StateFile", "identity"]

STATE_FORMAT = "burstloc-monitor-state/1"
"""Format tag of a monitor state file."""


def identity(
    config: Calibration, *, capture_interval: float, detector: str, localizer: str, meter_model: str
) -> dict[str, Any]:
    """What a state file is bound to (module docstring)."""
    text = json.dumps(config.to_json(), sort_keys=True, allow_nan=False)
    return {
        "network_hash": config.network_hash,
        "configuration": config.name,
        "configuration_sha256": hashlib.sha256(text.encode()).hexdigest(),
        "meters": list(config.meters),
        "capture_interval": capture_interval,
        "detector": detector,
        "localizer": localizer,
        "meter_model": meter_model,
    }


class StateFile:
    """The state file at ``path`` for the setup ``ident`` (:func:`identity`)."""

    def __init__(self, path: str | os.PathLike[str], ident: Mapping[str, Any]) -> None:
        self.path = Path(path)
        self.identity = dict(ident)

    def save(self, state: Mapping[str, Any]) -> None:
        """Write ``state`` atomically (a NaN or infinity is refused by the writer)."""
        write_json(
            self.path,
            {"format": STATE_FORMAT, "identity": self.identity, "state": dict(state)},
            indent=None,
        )

    def load(self) -> dict[str, Any] | None:
        """The saved state, or ``None`` when there is no file yet.

        Raises:
            ConfigError: unreadable, another format, or another setup (named field by field).
        """
        try:
            text = self.path.read_text(encoding="utf-8")
        except FileNotFoundError:
            return None
        except (OSError, UnicodeDecodeError) as exc:
            raise ConfigError(f"cannot read state file {str(self.path)!r}: {exc}") from exc
        try:
            doc = json.loads(text)
        except ValueError as exc:
            raise ConfigError(f"state file {str(self.path)!r} is not JSON: {exc}") from exc
        found = doc.get("format") if isinstance(doc, dict) else None
        if found != STATE_FORMAT:
            raise ConfigError(
                f"state file {str(self.path)!r} has format {found!r}, not {STATE_FORMAT!r}; "
                "remove it or give another --state file"
            )
        saved = doc.get("identity")
        if not isinstance(saved, dict) or not isinstance(doc.get("state"), dict):
            raise ConfigError(f"state file {str(self.path)!r} is malformed")
        differ = [k for k in self.identity if saved.get(k) != self.identity[k]]
        if differ:
            detail = "; ".join(f"{k}: {saved.get(k)!r}, not {self.identity[k]!r}" for k in differ)
            raise ConfigError(
                f"state file {str(self.path)!r} belongs to another network or configuration "
                f"({detail}); remove it or give another --state file"
            )
        state: dict[str, Any] = doc["state"]
        return state
