"""MQTT in and out: readings from a broker's topic, decision and health records to topics.

One :class:`MqttLink` is one paho-mqtt 2.x client (``CallbackAPIVersion.VERSION2``, MQTT 3.1.1,
QoS 1 both ways) with a persistent session (``clean_session=False`` and a stable client id):
while the monitor is down or reconnecting, the broker keeps the readings for it. Lost
connections are retried with backoff (1 s doubling to 30 s); every (re)connection subscribes
again. Each connection made and each one lost is reported (``connected to broker ...``,
``lost broker ...; reconnecting``); closing the link (:meth:`MqttLink.close`, e.g. on SIGTERM)
is not a lost connection and is not reported as one.

* **In**: every message on ``topic`` (MQTT wildcards allowed) goes into a bounded queue; the
  live loop takes messages from it (:meth:`MqttLink.messages`) and parses them
  (:func:`burstloc.live.parse.parse_payload`: JSON readings, batches, or CSV lines).
* **Backpressure**: the incoming queue holds at most ``queue_size`` messages. When it is full a
  new message is dropped, counted in :attr:`MqttLink.dropped` and reported; the network thread
  never blocks (a blocked thread would stop the keep-alive and lose the connection). Outgoing
  records wait in paho's queue of at most ``queue_size`` messages; a record that does not fit is
  counted in :attr:`MqttLink.unsent` and reported.
* **Out**: :meth:`MqttLink.publish` sends a record as JSON (QoS 1). Decisions and health go to
  their own topics through the same non-blocking queue: neither waits for the other.
* **Latency**: the client's socket has Nagle's algorithm off (``TCP_NODELAY``; paho leaves it
  on): a decision is a small packet written while the readings' acknowledgements flow, and with
  Nagle's algorithm it could wait for the broker's delayed ACK (40 ms and more on Linux) before
  leaving. The broker's own sockets are the broker's to configure (Mosquitto:
  ``set_tcp_nodelay true``).
"""

from __future__ import annotations

import contextlib
import json
import queue
import socket
import threading
from collections.abc import Callable, Iterator
from typing import Any

import paho.mqtt.client as mqtt
from paho.mqtt.enums import CallbackAPIVersion

from burstloc.exceptions import ConfigError

__all__ = ["MqttLink", "parse_address"]


def parse_address(text: str) -> tuple[str, int]:
    """``HOST:PORT`` (or ``HOST``: port 1883) → (host, port).

    Raises:
        ConfigError: an empty host or a port that is not 1-65535.
    """
    host, _, port_text = text.rpartition(":") if ":" in text else (text, "", "1883")
    try:
        port = int(port_text)
    except ValueError:
        port = -1
    if not host or not 0 < port < 65536:
        raise ConfigError(f"--mqtt wants HOST:PORT, got {text!r}")
    return host, port


class MqttLink:
    """One client for readings in and records out (module docstring)."""

    def __init__(
        self,
        host: str,
        port: int,
        topic: str,
        *,
        client_id: str,
        report: Callable[[str, str], None],
        queue_size: int = 100_000,
        keepalive: int = 30,
    ) -> None:
        self.topic = topic
        self.report = report
        self.dropped = 0
        self.unsent = 0
        self.received = 0
        #: The incoming queue's bound (messages).
        self.capacity = queue_size
        self.connected = threading.Event()
        self._queue: queue.Queue[tuple[int, bytes]] = queue.Queue(maxsize=queue_size)
        self._client = mqtt.Client(
            CallbackAPIVersion.VERSION2, client_id=client_id, clean_session=False
        )
        self._client.reconnect_delay_set(min_delay=1, max_delay=30)
        self._client.max_queued_messages_set(queue_size)
        self._client.on_socket_open = self._on_socket_open
        self._client.on_connect = self._on_connect
        self._client.on_disconnect = self._on_disconnect
        self._client.on_connect_fail = self._on_connect_fail
        self._client.on_message = self._on_message
        # Everything the callbacks read is set before the network thread starts: a connection
        # made at once calls them before this constructor's next line.
        self._address = f"{host}:{port}"
        self._last: mqtt.MQTTMessageInfo | None = None
        self._closing = False
        self._client.connect_async(host, port, keepalive=keepalive)
        self._client.loop_start()

    # ------------------------------------------------------- network thread
    def _on_socket_open(self, client: Any, userdata: Any, sock: Any) -> None:
        if isinstance(sock, socket.socket) and sock.family in (socket.AF_INET, socket.AF_INET6):
            try:
                sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            except OSError as exc:  # the link still works, only slower to send small records
                self.report("mqtt", f"cannot turn Nagle's algorithm off ({exc}); records may lag")

    def _on_connect(self, client: Any, userdata: Any, flags: Any, reason: Any, props: Any) -> None:
        if reason.is_failure:
            self.report("mqtt", f"broker {self._address} refused the connection: {reason}")
            return
        client.subscribe(self.topic, qos=1)
        self.connected.set()
        self.report("mqtt", f"connected to broker {self._address}, subscribed to {self.topic}")

    def _on_connect_fail(self, client: Any, userdata: Any) -> None:
        self.report("mqtt", f"cannot reach broker {self._address}; retrying")

    def _on_disconnect(
        self, client: Any, userdata: Any, flags: Any, reason: Any, props: Any
    ) -> None:
        self.connected.clear()
        if not self._closing:
            self.report("mqtt", f"lost broker {self._address} ({reason}); reconnecting")

    def _on_message(self, client: Any, userdata: Any, message: Any) -> None:
        self.received += 1
        try:
            self._queue.put_nowait((self.received, bytes(message.payload)))
        except queue.Full:
            self.dropped += 1
            self.report("mqtt", f"incoming queue full: message {self.received} dropped")

    # --------------------------------------------------------- main thread
    def wait_connected(self, timeout: float) -> bool:
        """Wait up to ``timeout`` s for the first connection; whether it is up."""
        return self.connected.wait(timeout)

    @property
    def queued(self) -> int:
        """Messages received and not yet taken by the loop (the incoming queue's depth)."""
        return self._queue.qsize()

    def messages(self, idle: float = 0.5) -> Iterator[tuple[int, bytes] | None]:
        """Messages as (number, payload), or ``None`` after ``idle`` s without one (forever)."""
        while True:
            try:
                yield self._queue.get(timeout=idle)
            except queue.Empty:
                yield None

    def publish(self, topic: str, record: dict[str, Any]) -> None:
        """Send ``record`` as JSON to ``topic`` (QoS 1), without waiting."""
        info = self._client.publish(topic, json.dumps(record), qos=1)
        self._last = info
        if info.rc == mqtt.MQTT_ERR_QUEUE_SIZE:
            self.unsent += 1
            self.report("mqtt", f"outgoing queue full: a record for {topic} was not sent")

    def close(self, timeout: float = 5.0) -> None:
        """Wait up to ``timeout`` s for outgoing records, then disconnect."""
        if self._last is not None and self._last.rc == mqtt.MQTT_ERR_SUCCESS:
            with contextlib.suppress(RuntimeError, ValueError):
                self._last.wait_for_publish(timeout)
        self._closing = True
        self._client.disconnect()
        self._client.loop_stop()
