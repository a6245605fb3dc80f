"""scripts/load_test.py's protocol client (``--client protocol``) against a real ``amra serve``:
sessions that speak Bokeh's websocket protocol without rendering open the page, press Run, see rows
stream and move the GJ slider, and every move's new GJ comes back to them in the streamed rows.

This checks that the client measures what it says (no errors, every session streamed, every move
seen by the server and by the client), not how fast: the figures depend on the machine.
"""
from __future__ import annotations

import math
import re
import sys

import pytest

from server_helpers import REPO

pytestmark = pytest.mark.slow
sys.path.insert(0, str(REPO / "scripts"))
import load_test  # noqa: E402


def test_protocol_client_sessions_stream_and_see_every_move(amra_server):
    base, srv = amra_server()
    n, moves = 2, 1
    # two client processes, one session each: the settled gate is shared across processes
    r = load_test.run_level_protocol(n, f"{base}/main", moves, timeout_s=60, run_s=20, stagger_s=0.25,
                                     settled=True, client_procs=2)
    print(f"\nprotocol N={n}: load p50 {r['load_p50_s']} s, Run -> first row p50 {r['run_first_p50_s']} s, "
          f"move p50 {r['p50_s']} s, client CPU {r['client_cpu_cores']} cores")
    assert r["errors"] == 0, r["error_samples"]
    assert r["client"] == "protocol" and r["client_procs"] == 2
    assert r["streamed_sessions"] == n
    assert r["load_p50_s"] is not None and r["run_first_p50_s"] is not None
    assert r["moves"] == n * moves
    assert r["settled"] and r["client_cpu_cores"] >= 0
    # each session started at its own GJ (1500, 1510) and moved about +0.13 decade; the client saw a
    # row with that GJ, and the server logged the change reaching it and its first rows going out
    log = srv.log_text()
    logged = {float(g) for g in re.findall(r"live change to GJ (\S+) N m", log)}
    step = 0.005  # the GJ slider's (app.inputs.gj_slider)
    expected = {float(f"{10 ** (round((math.log10(1500 + 10 * i) + 0.13) / step) * step):.4g}") for i in range(n)}
    assert expected <= logged, (expected, logged)
    assert len(re.findall(r"page built in", log)) == n
