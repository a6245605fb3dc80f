"""Server-side tuning of how Bokeh writes a message to a page's websocket: all of it at once.

A Bokeh message is several websocket frames: header, metadata, content, then a header and a payload
per binary buffer (a streamed batch of seven columns: 17 frames). ``Message.send`` writes them one
at a time and awaits each write. Each write is a Tornado task and a system call, so a message costs
about two event-loop turns per frame, and as many socket writes, each waking the browser's network
thread. The session's document lock and the connection's write lock are held all that time.

On a loaded server every turn is long. With eight browsers streaming on the server's two cores, the
server's event loop ran only 14 % of the time, and half of that was in socket writes (py-spy,
2026-12-02). The reply to a page's message took 49 ms on average and 320 ms at p95, and the wait
for the document lock 43 / 259 ms (a probe of ``amra serve`` under ``scripts/load_test.py
--sessions 8``). A connection's messages are handled one after another, so a slider change could
queue behind the page's drawn-batch confirmations for up to 1.4 s before the server read it.

:func:`install` makes ``Message.send`` write a message in one go:

* on a plain server connection (frames neither masked nor compressed, as ``amra serve`` runs it),
  all frames are framed as Tornado frames them (RFC 6455 section 5.2: final bit, opcode, length)
  and written to the stream with one call;
* otherwise, all frames are queued through Tornado's own ``write_message`` before the first one is
  awaited.

Either way the bytes on the wire and their order are Bokeh's, and a message costs one system call
or one write per frame, and one or two event-loop turns. Bokeh's own client connections
(``bokeh.client``) keep Bokeh's way. The patch is installed once per process, and only if Bokeh's
and Tornado's internals look as expected. ``tests/app/test_socket_tuning.py`` checks that a real
websocket client receives Bokeh's frames, and counts the writes and the turns.
"""
from __future__ import annotations

import asyncio
import inspect
import json
import struct

from bokeh.core.serialization import Buffer
from bokeh.protocol.message import Message
from tornado.iostream import StreamClosedError
from tornado.websocket import WebSocketClosedError, WebSocketHandler, WebSocketProtocol13

_write = WebSocketHandler.write_message  #: Tornado's write of one frame (queued at once; returns a future)


def frames(message: Message) -> list:
    """``(data, binary)`` of each websocket frame of ``message``, in Bokeh's order."""
    out = [(message.header_json, False), (message.metadata_json, False), (message.content_json, False)]
    for buffer in message._buffers:
        out += [(json.dumps(buffer.ref), False), (buffer.to_bytes(), True)]
    return out


def frame_bytes(payload: bytes, binary: bool) -> list:
    """An unmasked, uncompressed, final websocket frame: ``[head, payload]`` (RFC 6455 5.2)."""
    first = 0x80 | (0x2 if binary else 0x1)
    n = len(payload)
    if n < 126:
        head = struct.pack("!BB", first, n)
    elif n <= 0xFFFF:
        head = struct.pack("!BBH", first, 126, n)
    else:
        head = struct.pack("!BBQ", first, 127, n)
    return [head, payload]


def _plain(protocol) -> bool:
    """A connection whose frames Tornado writes as :func:`frame_bytes` makes them, with the
    attributes :func:`_write_at_once` uses (a Tornado that lacks one takes the queued path)."""
    return (type(protocol) is WebSocketProtocol13 and getattr(protocol, "mask_outgoing", True) is False
            and getattr(protocol, "_compressor", True) is None and getattr(protocol, "stream", None) is not None
            and all(isinstance(getattr(protocol, a, None), int) for a in ("_message_bytes_out", "_wire_bytes_out")))


def _looks_as_expected() -> bool:
    from bokeh.protocol import Protocol
    probe = Protocol().create("OK", "probe")
    return (inspect.iscoroutinefunction(Message.send) and isinstance(getattr(probe, "_buffers", None), list)
            and isinstance(probe.header_json, str) and isinstance(getattr(Buffer, "ref", None), property)
            and callable(getattr(Buffer, "to_bytes", None)) and callable(getattr(WebSocketProtocol13, "is_closing", None)))


async def _write_at_once(conn, message: Message) -> int:
    protocol = conn.ws_connection
    if protocol is None or protocol.is_closing():
        raise WebSocketClosedError()
    parts, sent, payload_bytes = [], 0, 0
    for data, binary in frames(message):
        payload = data.encode("utf-8") if isinstance(data, str) else bytes(data)
        parts += frame_bytes(payload, binary)
        sent += len(data)
        payload_bytes += len(payload)
    wire = b"".join(parts)
    protocol._message_bytes_out += payload_bytes  # Tornado's counters, as its own writes keep them
    protocol._wire_bytes_out += len(wire)
    try:
        await protocol.stream.write(wire)
    except StreamClosedError:
        raise WebSocketClosedError()
    return sent


async def _queue_then_await(conn, message: Message) -> int:
    writes, sent = [], 0
    try:
        for data, binary in frames(message):
            writes.append(_write(conn, data, binary=binary))
            sent += len(data)
    finally:  # a closed socket raises at once: still collect what was queued
        results = await asyncio.gather(*writes, return_exceptions=True)
    for r in results:
        if isinstance(r, BaseException):
            raise r
    return sent


def install() -> bool:
    """Patch Bokeh (once per process); returns whether the patch is in place."""
    if getattr(Message, "_amra_one_go", False):
        return True
    if not _looks_as_expected():
        return False
    bokeh_send = Message.send

    async def send(self, conn) -> int:
        if not isinstance(conn, WebSocketHandler):
            return await bokeh_send(self, conn)
        with await conn.write_lock.acquire():
            if conn.ws_connection is not None and _plain(conn.ws_connection):
                return await _write_at_once(conn, self)
            return await _queue_then_await(conn, self)

    send.__doc__ = bokeh_send.__doc__
    Message.send = send
    Message._amra_bokeh_send = bokeh_send  # Bokeh's own, for comparison (tests)
    Message._amra_one_go = True
    return True
