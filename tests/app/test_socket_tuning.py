"""A Bokeh message written in one go (app.socket_tuning) reaches a real websocket client as the same
frames, in the same order, as Bokeh's own frame-by-frame send, in one socket write and one event-loop
turn (all frames queued at once where the frames are not plain: four turns) instead of two turns per
frame."""
from __future__ import annotations

import asyncio
import socket
import sys
from pathlib import Path

import numpy as np
import pytest
import tornado.locks
import tornado.web
import tornado.websocket
from bokeh.document import Document
from bokeh.models import ColumnDataSource
from bokeh.protocol import Protocol
from bokeh.protocol.message import Message

from app import socket_tuning

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "scripts"))
from load_test import run_async  # noqa: E402 - asyncio.run in a thread of its own (a test's loop may run)

COLUMNS = "abcdefg"  # as many columns as the live plots' source


def _streamed_message(rows: int = 50) -> Message:
    """A PATCH-DOC of a streamed batch: header, metadata, content and seven binary buffers."""
    doc = Document()
    source = ColumnDataSource({c: np.zeros(0) for c in COLUMNS})
    doc.add_root(source)
    doc.models.flush_synced()
    events = []
    doc.on_change(events.append)
    source.stream({c: np.arange(rows, dtype=float) * (k + 1) for k, c in enumerate(COLUMNS)}, rollover=1000)
    msg = Protocol().create("PATCH-DOC", events)
    assert len(msg._buffers) == len(COLUMNS)
    return msg


class _Page(tornado.websocket.WebSocketHandler):
    """The server end of a page's websocket, with Bokeh's write lock and its locked write
    (``bokeh.server.views.ws.WSHandler.write_message``)."""

    def open(self):
        self.write_lock = tornado.locks.Lock()
        self.application.settings["opened"].set_result(self)

    async def write_message(self, message, binary=False, locked=True):
        if locked:
            with await self.write_lock.acquire():
                await super().write_message(message, binary)
        else:
            await super().write_message(message, binary)


async def _pair():
    """A Tornado websocket server and a client connected to it: (server handler, client, server)."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    opened = asyncio.get_running_loop().create_future()
    app = tornado.web.Application([("/ws", _Page)], opened=opened)
    server = app.listen(port, address="127.0.0.1")
    client = await tornado.websocket.websocket_connect(f"ws://127.0.0.1:{port}/ws")
    handler = await opened
    return handler, client, server


async def _turns_while(coro) -> tuple:
    """Run ``coro``; return its result and how many event-loop turns it took."""
    task = asyncio.ensure_future(coro)
    turns = 0
    while not task.done():
        await asyncio.sleep(0)
        turns += 1
    return task.result(), turns


async def _received(client, n: int) -> list:
    return [await client.read_message() for _ in range(n)]


def test_install_is_idempotent_and_in_place():
    assert socket_tuning.install() and socket_tuning.install()
    assert getattr(Message, "_amra_one_go", False)


@pytest.mark.parametrize("plain", [True, False], ids=["one-write", "queued-frames"])
@pytest.mark.parametrize("rows", [50, 5_000, 10_000])  # buffers of 400 B, 40 kB, 80 kB: all three length codes
def test_a_streamed_batch_arrives_as_bokehs_frames_in_a_few_turns(rows, plain, monkeypatch):
    assert socket_tuning.install()
    if not plain:  # as on a compressed connection: each frame through Tornado's own write
        monkeypatch.setattr(socket_tuning, "_plain", lambda protocol: False)
    msg = _streamed_message(rows)
    expected = [data for data, _ in socket_tuning.frames(msg)]
    assert len(expected) == 3 + 2 * len(COLUMNS)

    class Recorder:  # not a websocket handler: the patched send leaves it to Bokeh's own code
        write_lock = tornado.locks.Lock()
        written: list = []

        async def write_message(self, data, binary=False, locked=True):
            self.written.append(data)

    async def go():
        rec = Recorder()
        bokeh_bytes = await msg.send(rec)
        handler, client, server = await _pair()
        stream = handler.ws_connection.stream
        writes = []
        real_write = stream.write
        monkeypatch.setattr(stream, "write", lambda data: writes.append(len(data)) or real_write(data))
        try:
            proto = handler.ws_connection
            counters = lambda: (proto._message_bytes_out, proto._wire_bytes_out)  # noqa: E731
            c0 = counters()
            sent, turns = await _turns_while(msg.send(handler))
            c1 = counters()
            got = await _received(client, len(expected))
            ours = list(writes)
            _, bokeh_turns = await _turns_while(Message._amra_bokeh_send(msg, handler))
            c2 = counters()
            counted.update(ours=(c1[0] - c0[0], c1[1] - c0[1]), bokehs=(c2[0] - c1[0], c2[1] - c1[1]))
            got_again = await _received(client, len(expected))
        finally:
            client.close()
            server.stop()
        return rec.written, bokeh_bytes, sent, turns, got, bokeh_turns, got_again, ours, writes[len(ours):]

    counted = {}
    written, bokeh_bytes, sent, turns, got, bokeh_turns, got_again, ours, bokehs = run_async(go())
    assert counted["ours"] == counted["bokehs"], counted  # Tornado's byte counters kept as its own writes keep them
    assert written == expected and got == expected and got_again == expected  # same frames, same order
    assert sent == bokeh_bytes == sum(len(d) for d in expected)
    assert sum(ours) == sum(bokehs) and len(bokehs) == len(expected)  # the same bytes on the wire
    assert len(ours) == (1 if plain else len(expected))
    print(f"rows {rows}: turns one go {turns}, Bokeh frame by frame {bokeh_turns}; writes {len(ours)}")
    assert turns == (1 if plain else 4) and 4 < 2 * len(expected) <= bokeh_turns, (turns, bokeh_turns)


def test_a_closed_socket_raises_as_bokehs_send_does():
    assert socket_tuning.install()
    msg = _streamed_message(5)

    async def go():
        handler, client, server = await _pair()
        client.close()
        for _ in range(200):  # until the server has seen the close
            if handler.ws_connection is None or handler.ws_connection.is_closing():
                break
            await asyncio.sleep(0.01)
        server.stop()
        try:
            await msg.send(handler)
        except tornado.websocket.WebSocketClosedError:
            return "closed"
        return "sent"

    assert run_async(go()) == "closed"
