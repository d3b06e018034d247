"""The errors of the incident store, typed so that callers catch precisely.

* :class:`IncidentError` (:class:`~burstloc.exceptions.InputError`, so a ``ValueError``): an
  operator's request the store refuses; the base of the two below.
* :class:`UnknownIncidentError`: no incident with that number in the store.
* :class:`IncidentStateError`: an action the incident's state does not allow (acknowledging a
  closed incident, dispatching one nobody acknowledged); names the incident, its state, the
  action and the states that allow it.
* :class:`IncidentStoreError` (:class:`~burstloc.exceptions.ConfigError`): the store cannot be
  used: a malformed address, a database that cannot be reached or opened, a schema newer than
  this burstloc knows, the ``incidents`` extra not installed.
"""

from __future__ import annotations

from collections.abc import Sequence

from burstloc.exceptions import ConfigError, InputError

__all__ = ["IncidentError", "IncidentStateError", "IncidentStoreError", "UnknownIncidentError"]


class IncidentError(InputError):
    """An operator's request the incident store refuses."""


class UnknownIncidentError(IncidentError):
    """No incident with this number in the store."""

    def __init__(self, incident: int, store: str) -> None:
        self.incident = incident
        super().__init__(f"no incident {incident} in the incident store {store}")


class IncidentStateError(IncidentError):
    """An action the incident's state does not allow.

    Args:
        incident: the incident's number.
        state: its state.
        action: the action refused.
        allowed: the states from which ``action`` is allowed.
    """

    def __init__(self, incident: int, state: str, action: str, allowed: Sequence[str]) -> None:
        self.incident, self.state, self.action = incident, state, action
        self.allowed = tuple(allowed)
        need = " or ".join(self.allowed) if self.allowed else "no state"
        super().__init__(
            f"incident {incident} is {state}: it cannot be {_past(action)} "
            f"(only an incident that is {need} can)"
        )


class IncidentStoreError(ConfigError):
    """The incident store cannot be used (module docstring)."""


def _past(action: str) -> str:
    return {
        "acknowledge": "acknowledged",
        "dispatch": "dispatched",
        "close": "closed",
        "note": "annotated",
        "shelve": "shelved",
        "unshelve": "unshelved",
    }.get(action, action)
