"""A per-session 'latest wins' background thread for one-shot analyses (modes, locus, fan plot).

``submit(key, fn)`` replaces whatever was queued under ``key``; a running job's ``cancel`` event
is set when a newer one for the same key arrives. Results go out through ``post`` like the run
worker's, so the document is only touched on the session's event loop.
"""
from __future__ import annotations

import threading
from typing import Callable


class LatestTasks:
    def __init__(self, post: Callable[[str, dict], None]):
        self._post = post
        self._cond = threading.Condition()
        self._queued: dict = {}
        self._cancel: dict = {}
        self._closed = False
        self._thread = threading.Thread(target=self._loop, name="amra-analysis", daemon=True)
        self._thread.start()

    def submit(self, key: str, fn: Callable[[threading.Event], dict]) -> None:
        """Run ``fn(cancel_event)`` soon; its dict result is posted as ``(key, result)``."""
        with self._cond:
            old = self._cancel.get(key)
            if old is not None:
                old.set()
            self._queued[key] = fn
            self._cond.notify()

    def idle(self) -> bool:
        with self._cond:
            return not self._queued and not self._cancel

    def close(self) -> None:
        with self._cond:
            self._closed = True
            for ev in self._cancel.values():
                ev.set()
            self._cond.notify()
        self._thread.join(5.0)

    def _loop(self) -> None:
        from .server_limits import lower_priority_of_this_thread
        lower_priority_of_this_thread()  # analyses yield the CPU to the live run (server_limits)
        while True:
            with self._cond:
                while not self._queued and not self._closed:
                    self._cond.wait()
                if self._closed:
                    return
                key, fn = next(iter(self._queued.items()))
                del self._queued[key]
                cancel = threading.Event()
                self._cancel[key] = cancel
            try:
                result = fn(cancel)
                if not cancel.is_set():
                    self._post(key, result)
            except Exception as exc:  # noqa: BLE001 - reported in the page
                if not cancel.is_set():
                    self._post("error", {"text": f"{key} failed: {exc}"})
            finally:
                with self._cond:
                    if self._cancel.get(key) is cancel:
                        del self._cancel[key]
