"""burstloc.live.mqtt: ``burstloc monitor --mqtt`` against a real Mosquitto broker."""

from __future__ import annotations

import json
import queue
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import paho.mqtt.client as mqtt
import pytest
from live_feed import burst_steps
from mosquitto import SUBSCRIPTIONS, broker
from paho.mqtt.enums import CallbackAPIVersion

from burstloc.exceptions import ConfigError
from burstloc.experiments.calibrate import calibrate
from burstloc.live.mqtt import MqttLink, parse_address

PIPE = "C"
#: Seconds after which a test that waits for the monitor gives up: a guard against a hang, far
#: beyond what the slowest machine needs (nothing here is timed).
HANG_GUARD = 600


@pytest.fixture(scope="module")
def mqtt_port(tmp_path_factory: pytest.TempPathFactory) -> Iterator[int]:
    """The port of a real Mosquitto broker on 127.0.0.1, running for this module's tests."""
    with broker(tmp_path_factory.mktemp("mosquitto")) as port:
        yield port


def _client(port: int, name: str) -> mqtt.Client:
    client = mqtt.Client(CallbackAPIVersion.VERSION2, client_id=name)
    client.connect("127.0.0.1", port)
    client.loop_start()
    return client


def _next(
    got: queue.Queue[tuple[str, Any]], monitor: subprocess.Popen[str], hang: float, what: str
) -> tuple[str, Any]:
    """The next message the listener got, while the monitor runs (waiting for ``what``)."""
    while True:
        try:
            return got.get(timeout=1)
        except queue.Empty:
            assert monitor.poll() is None, f"the monitor ended before {what}"
            assert time.monotonic() < hang, f"no {what} on the broker"


def test_readings_in_and_decisions_out_through_the_broker(
    tiny: Path, tmp_path: Path, mqtt_port: int
) -> None:
    config = calibrate(tiny, capture_intervals=(0.2,), noise_sigma=0.01)
    cfg = config.save(tmp_path / "tiny.json")
    steps = burst_steps(tiny, config.meters, PIPE, sigma=0.002, after=200.0)
    got: queue.Queue[tuple[str, Any]] = queue.Queue()
    hang = time.monotonic() + HANG_GUARD
    listener = _client(mqtt_port, "listener")
    listener.on_message = lambda c, u, m: got.put(
        (m.topic, m.payload.decode() if m.topic == SUBSCRIPTIONS else json.loads(m.payload))
    )
    listener.subscribe("burstloc/decisions", qos=1)
    listener.subscribe("burstloc/health", qos=1)
    listener.subscribe(SUBSCRIPTIONS, qos=1)
    argv = [sys.executable, "-m", "burstloc", "monitor", str(tiny), "--config", str(cfg)]
    argv += ["--capture-interval", "0.2", "--mqtt", f"127.0.0.1:{mqtt_port}"]
    argv += ["--topic", "plant/readings/#", "--health-every", "30"]
    monitor = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        # Readings sent before the monitor has subscribed would be lost: wait for the broker to
        # log its subscription (however long the monitor takes to start on a loaded machine).
        while True:
            topic, record = _next(got, monitor, hang, "subscribing")
            if topic == SUBSCRIPTIONS and record.endswith(" plant/readings/#"):
                break
        sender = _client(mqtt_port, "sender")
        infos = [sender.publish("plant/readings/x", b"{broken", qos=1)]
        infos.append(sender.publish("plant/readings/x", b"1.0,J1,not-a-number", qos=1))
        for s in steps:
            batch = [
                {"t": s.timestamp, "meter": m, "value": float(v)}
                for m, v in zip(config.meters, s.values, strict=True)
            ]
            infos.append(sender.publish("plant/readings/all", json.dumps(batch), qos=1))
        for info in infos:
            info.wait_for_publish(10)
        decisions, health = [], []
        while not decisions or not health:  # the monitor answers, or ends and fails the test
            topic, record = _next(got, monitor, hang, "a decision and a health record")
            if topic != SUBSCRIPTIONS:
                (decisions if topic == "burstloc/decisions" else health).append(record)
        assert decisions[0]["type"] == "decision" and decisions[0]["pipes"][0]["pipe"] == PIPE
        assert health[0]["type"] == "health"
    finally:
        monitor.send_signal(signal.SIGTERM)
        _, err = monitor.communicate(timeout=30)
        listener.loop_stop()
    assert monitor.returncode == 0, err
    assert "payload is not valid JSON" in err and "value is not a finite number" in err


def test_broker_address_is_checked() -> None:
    assert parse_address("localhost") == ("localhost", 1883)
    assert parse_address("10.0.0.2:1884") == ("10.0.0.2", 1884)
    for bad in ("host:0", ":1883", "host:x", "host:70000"):
        with pytest.raises(ConfigError, match="HOST:PORT"):
            parse_address(bad)


def test_the_link_sends_small_records_without_nagle_delay(mqtt_port: int) -> None:
    # A decision is one small packet: with Nagle's algorithm on (paho's default) it could wait
    # for the broker's delayed acknowledgement of the previous one before leaving.
    messages: list[str] = []
    link = MqttLink(
        "127.0.0.1",
        mqtt_port,
        "plant/readings/#",
        client_id="nodelay-check",
        report=lambda kind, text: messages.append(text),
    )
    try:
        assert link.wait_connected(HANG_GUARD), messages
        sock = link._client.socket()
        assert sock is not None
        assert sock.getsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY) != 0
    finally:
        link.close()
    assert not any("Nagle" in text for text in messages), messages


def test_a_connection_made_at_once_finds_the_link_ready(monkeypatch: pytest.MonkeyPatch) -> None:
    # The network thread may connect before the constructor returns: its callbacks then read
    # the link (the broker's address for the "connected" line). Here the connection is made
    # the moment the thread starts; before the fix the callback raised AttributeError, which
    # ended paho's network thread: no reading would ever have been received.
    import paho.mqtt.client as paho

    messages: list[str] = []

    def connect_at_once(client: paho.Client) -> None:
        reason = paho.ReasonCode(paho.PacketTypes.CONNACK, identifier=0)
        client.on_connect(client, None, None, reason, None)

    monkeypatch.setattr(paho.Client, "loop_start", connect_at_once)
    monkeypatch.setattr(paho.Client, "subscribe", lambda client, topic, qos: None)
    link = MqttLink(
        "127.0.0.1", 1, "plant/#", client_id="at-once", report=lambda k, t: messages.append(t)
    )
    assert link.connected.is_set()
    assert messages == ["connected to broker 127.0.0.1:1, subscribed to plant/#"]
