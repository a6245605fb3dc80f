"""Running a coroutine from a test, wherever the test runs."""
from __future__ import annotations


def run_coroutine(coro):
    """``asyncio.run(coro)`` in a thread of its own: the browser tests' sync Playwright leaves an
    event loop running in the main thread, where ``asyncio.run`` refuses to start."""
    import asyncio
    import threading
    out = {}

    def target():
        try:
            out["value"] = asyncio.run(coro)
        except BaseException as exc:  # noqa: BLE001 - re-raised in the caller's thread
            out["error"] = exc
    t = threading.Thread(target=target, name="amra-test-loop")
    t.start()
    t.join()
    if "error" in out:
        raise out["error"]
    return out.get("value")
