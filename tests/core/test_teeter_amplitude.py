"""The teeter amplitude paper Table 1 compares with flight: one definition (the first harmonic over
the last revolution, :func:`amra_core.verdict.teeter_amplitude_rad`) for the trim, a run, the CLI and
the dashboard."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

from amra_core.kernels import HISTORY_COLUMNS
from amra_core.verdict import teeter_amplitude_rad


def _history(t, omega, beta):
    h = np.zeros((len(t), len(HISTORY_COLUMNS)))
    h[:, HISTORY_COLUMNS.index("t_s")] = t
    h[:, HISTORY_COLUMNS.index("omega_rad_s")] = omega
    h[:, HISTORY_COLUMNS.index("azimuth_rad")] = omega * t
    h[:, HISTORY_COLUMNS.index("teeter_rad")] = beta
    return h


@pytest.mark.parametrize("phase", [0.0, 0.7, -2.0])
def test_a_pure_one_per_rev_teeter_with_an_offset_and_a_2_per_rev_part_has_its_first_harmonic(phase):
    """beta = 0.03 cos(psi + phase) + 0.004 + 0.01 cos(2 psi): the 1/rev amplitude is 0.03 exactly
    (a whole revolution of samples; the peak |beta| would be 0.044)."""
    omega = 38.0
    dt = 2 * math.pi / omega / 200  # 200 samples per revolution
    t = np.arange(0, 2000) * dt
    psi = omega * t
    beta = 0.03 * np.cos(psi + phase) + 0.004 + 0.01 * np.cos(2 * psi)
    assert teeter_amplitude_rad(_history(t, omega, beta)) == pytest.approx(0.03, rel=1e-9)


def test_an_empty_history_has_no_amplitude():
    assert math.isnan(teeter_amplitude_rad(np.zeros((0, len(HISTORY_COLUMNS)))))


def test_the_cli_reports_the_runs_first_harmonic(tmp_path, capsys):
    """``amra simulate`` (it reported the peak |beta| of the last revolution) and the run's own
    history, read back from its CSV, give one number."""
    from amra_core.cli import main
    out = tmp_path / "h.csv"
    assert main(["simulate", "--preset", "mccutcheon", "--airspeed", "14", "--t-end", "2", "--json",
                 "--out", str(out)]) == 0
    d = json.loads(capsys.readouterr().out)
    rows = [line for line in out.read_text().splitlines() if line and not line.startswith("#")]
    header, data = rows[0].split(","), np.array([[float(x) for x in r.split(",")] for r in rows[1:]])
    assert header == list(HISTORY_COLUMNS)
    assert d["teeter_amplitude_rad"] == pytest.approx(teeter_amplitude_rad(data), rel=1e-6)
    assert 0.0 < d["teeter_amplitude_rad"] < 0.2
