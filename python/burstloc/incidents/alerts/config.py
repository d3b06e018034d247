"""What the webhook alerts are told to do: the receivers' URLs, checked, and the limits of
delivery (:class:`WebhookSettings`). Pure: no database, no network."""

from __future__ import annotations

import math
import urllib.parse
from dataclasses import dataclass
from pathlib import Path

from burstloc.exceptions import ConfigError

__all__ = [
    "MAX_AGE",
    "MAX_ATTEMPTS",
    "RETRY",
    "TIMEOUT",
    "WebhookSettings",
    "check_url",
    "shown",
]

#: Seconds an attempt waits for the receiver's answer.
TIMEOUT = 10.0
#: Seconds (the alerts' clock) before the second attempt, doubling each time, and the most.
RETRY = (2.0, 300.0)
#: Attempts after which an alert is given up (to the dead-letter file).
MAX_ATTEMPTS = 100
#: Seconds (the alerts' clock) after it became due after which an alert is given up, once tried.
MAX_AGE = 6 * 3600.0


def check_url(url: str) -> str:
    """``url`` if it is an ``http://`` or ``https://`` URL with a host (and a valid port).

    Raises:
        ValueError: it is not, saying why.
    """
    if not isinstance(url, str) or not url.strip() or any(c.isspace() for c in url):
        raise ValueError(f"want an http:// or https:// URL, got {url!r}")
    try:
        parts = urllib.parse.urlsplit(url)
        parts.port  # noqa: B018  (raises on a bad port)
    except ValueError as exc:
        raise ValueError(f"{shown(url)!r} is not a URL: {exc}") from None
    if parts.scheme not in ("http", "https"):
        raise ValueError(f"want an http:// or https:// URL, got {shown(url)!r}")
    if not parts.hostname:
        raise ValueError(f"{shown(url)!r} names no host")
    return url


def shown(url: str) -> str:
    """``url`` as told to a person: without its user, password and query (they may hold a
    secret)."""
    try:
        parts = urllib.parse.urlsplit(url)
        host = parts.hostname or ""
        port = parts.port
    except ValueError:
        return url.split("?")[0].split("@")[-1]
    host = f"[{host}]" if ":" in host else host
    where = host if port is None else f"{host}:{port}"
    query = "?…" if parts.query else ""
    return f"{parts.scheme}://{where}{parts.path}{query}"


@dataclass(frozen=True)
class WebhookSettings:
    """The webhooks of one monitor.

    ``urls``: the receivers, each sent every alert; ``escalate_after``: seconds (the alerts'
    clock) an incident may stay unacknowledged before it is alerted again (``None``: never);
    ``dead_letter``: the JSON-lines file of the alerts given up; ``timeout``, ``retry``,
    ``max_attempts``, ``max_age``: the module's constants unless given.

    Raises:
        ConfigError: no URL, a bad URL, a repeated URL, a non-positive or non-finite number
            (each named by its settings key).
    """

    urls: tuple[str, ...]
    dead_letter: Path
    escalate_after: float | None = None
    timeout: float = TIMEOUT
    retry: tuple[float, float] = RETRY
    max_attempts: int = MAX_ATTEMPTS
    max_age: float = MAX_AGE

    def __post_init__(self) -> None:
        if not self.urls:
            raise ConfigError("webhook: give at least one URL")
        for url in self.urls:
            try:
                check_url(url)
            except ValueError as exc:
                raise ConfigError(f"webhook: {exc}") from None
        if len(set(self.urls)) != len(self.urls):
            raise ConfigError("webhook: a URL is given twice (each gets every alert once)")
        numbers = {
            "webhook-escalate-minutes": None
            if self.escalate_after is None
            else self.escalate_after / 60,
            "timeout": self.timeout,
            "retry": self.retry[0],
            "retry cap": self.retry[1],
            "max-age": self.max_age,
        }
        for key, value in numbers.items():
            if value is not None and not (math.isfinite(value) and value > 0):
                raise ConfigError(f"{key} must be a finite number > 0, got {value}")
        if self.retry[1] < self.retry[0]:
            raise ConfigError(f"the retry cap {self.retry[1]} is below its start {self.retry[0]}")
        if self.max_attempts < 1:
            raise ConfigError(f"max-attempts must be >= 1, got {self.max_attempts}")

    def backoff(self, attempts: int) -> float:
        """Seconds (the alerts' clock) before the attempt after ``attempts`` failed ones."""
        return float(min(self.retry[0] * 2 ** min(attempts - 1, 60), self.retry[1]))
