"""Fixtures of the live tests: a real Mosquitto broker."""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from mosquitto import broker


@pytest.fixture(scope="module")
def mqtt_port(tmp_path_factory: pytest.TempPathFactory) -> Iterator[int]:
    """The port of a Mosquitto broker on 127.0.0.1, running for the module's tests."""
    with broker(tmp_path_factory.mktemp("mosquitto")) as port:
        yield port
