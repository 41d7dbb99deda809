"""MQTT brokers and clients: the embedded default broker and connections to any broker by URL.

The embedded broker is amqtt, a pure-Python MQTT 3.1.1 broker, run on its own event loop in a
background thread of the executor's process and bound to a free loopback port, so ``bille run``
needs no set-up. Any external broker (mosquitto, say) is reached by ``mqtt://host:port``.
"""
from __future__ import annotations

import asyncio
import gc
import logging
import socket
import threading
import warnings
from dataclasses import dataclass
from urllib.parse import urlsplit

import paho.mqtt.client as mqtt

from .protocol import ExecutionError

DEFAULT_PORT = 1883


@dataclass(frozen=True)
class BrokerURL:
    host: str
    port: int

    def __str__(self) -> str:
        return f"mqtt://{self.host}:{self.port}"


def parse_url(url: str) -> BrokerURL:
    """``mqtt://host[:port]`` (or ``host[:port]``) -> :class:`BrokerURL`.

    >>> parse_url("mqtt://127.0.0.1:1884")
    BrokerURL(host='127.0.0.1', port=1884)
    """
    parts = urlsplit(url if "://" in url else f"mqtt://{url}")
    try:
        port = parts.port or DEFAULT_PORT
    except ValueError:
        port = None
    if parts.scheme != "mqtt" or not parts.hostname or port is None or parts.path not in ("", "/"):
        raise ExecutionError(f"--broker: {url!r} is not a broker URL (expected mqtt://host:port)")
    return BrokerURL(parts.hostname, port)


def free_port(host: str = "127.0.0.1") -> int:
    with socket.socket() as s:
        s.bind((host, 0))
        return s.getsockname()[1]


class EmbeddedBroker:
    """An amqtt broker on ``host`` (loopback unless told otherwise) in a background thread.

    Use as a context manager; ``url`` is where clients connect.
    """

    def __init__(self, host: str = "127.0.0.1", port: int | None = None):
        self.url = BrokerURL(host, port or free_port(host))
        self._loop = asyncio.new_event_loop()
        self._thread = threading.Thread(target=self._serve, name="bille-broker", daemon=True)
        self._ready = threading.Event()
        self._broker = None
        self._error: BaseException | None = None

    def _serve(self) -> None:
        from amqtt.broker import Broker

        asyncio.set_event_loop(self._loop)
        logging.getLogger("amqtt").setLevel(logging.CRITICAL)  # it logs every connection at INFO
        # a client session that fails inside amqtt ends that connection only (the client
        # reconnects); keep its traceback out of the user's terminal
        self._loop.set_exception_handler(lambda loop, context: logging.getLogger("bille.broker").debug(
            "embedded broker: %s", context.get("message")))

        async def start():
            config = {
                "listeners": {"default": {"type": "tcp", "bind": f"{self.url.host}:{self.url.port}"}},
                "plugins": {"amqtt.plugins.authentication.AnonymousAuthPlugin": {"allow_anonymous": True}},
            }
            self._broker = Broker(config)
            await self._broker.start()

        try:
            self._loop.run_until_complete(start())
        except BaseException as exc:  # reported by start() in the caller's thread
            self._error = exc
            self._ready.set()
            return
        self._ready.set()
        self._loop.run_forever()

    def start(self) -> "EmbeddedBroker":
        self._thread.start()
        self._ready.wait(10)
        if self._error is not None or self._broker is None:
            raise ExecutionError(f"cannot start the embedded broker on {self.url}: {self._error}")
        return self

    def stop(self) -> None:
        if self._broker is not None and self._loop.is_running():
            fut = asyncio.run_coroutine_threadsafe(self._broker.shutdown(), self._loop)
            try:
                fut.result(5)
            except Exception:  # noqa: BLE001 - shutting down anyway
                pass
            self._loop.call_soon_threadsafe(self._loop.stop)
            self._thread.join(5)
        if not self._loop.is_running() and not self._loop.is_closed():
            self._loop.close()
        # amqtt's shutdown leaves client connections' transports behind; close them now, here,
        # rather than whenever the collector meets them (with a ResourceWarning each)
        self._broker = None
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ResourceWarning)
            gc.collect()

    def __enter__(self) -> "EmbeddedBroker":
        return self.start()

    def __exit__(self, *exc) -> None:
        self.stop()


def connect(url: BrokerURL, client_id: str, *, will: tuple[str, bytes] | None = None,
            on_message=None, on_connected=None, on_disconnected=None, keepalive: int = 10,
            timeout: float = 5.0) -> mqtt.Client:
    """A connected paho client with its network loop running in a thread; it reconnects by itself.

    ``will`` is ``(topic, payload)``, published retained by the broker if the connection breaks.
    ``on_connected(client)`` runs after every (re)connection (subscribe there: a clean session
    forgets subscriptions), ``on_disconnected(client)`` after every loss, before reconnecting.
    Raises :class:`ExecutionError` when the broker cannot be reached.
    """
    client = mqtt.Client(mqtt.CallbackAPIVersion.VERSION2, client_id=client_id, clean_session=True)
    if will is not None:
        client.will_set(will[0], will[1], qos=1, retain=True)
    if on_message is not None:
        client.on_message = on_message
    connected = threading.Event()

    def connected_now(c, userdata, flags, reason, props=None):
        if on_connected is not None:
            on_connected(c)
        connected.set()

    client.on_connect = connected_now
    if on_disconnected is not None:
        client.on_disconnect = lambda c, userdata, flags, reason, props=None: on_disconnected(c)
    try:
        client.connect(url.host, url.port, keepalive=keepalive)
    except (OSError, ValueError) as exc:
        reason = getattr(exc, "strerror", None) or str(exc)
        raise ExecutionError(f"cannot reach the broker at {url}: {reason}") from None
    sock = client.socket()
    if sock is not None:  # small messages, one at a time: no Nagle delay
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    client.loop_start()
    if not connected.wait(timeout):
        client.loop_stop()
        raise ExecutionError(f"cannot reach the broker at {url}: no answer to CONNECT within {timeout:g} s")
    return client


def close(client: mqtt.Client) -> None:
    """Disconnect cleanly (no last will) and stop the network thread."""
    try:
        client.disconnect()
    finally:
        client.loop_stop()
