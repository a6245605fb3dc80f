"""AMRA dashboard entry point (placeholder).

Served with ``panel serve app/main.py`` (see ``scripts/dashboard.sh``). Panel runs
this script once per browser session, and everything is built inside
:func:`create_app`, so no state is shared between sessions. This placeholder does
not import :mod:`amra_core`.
"""

from __future__ import annotations

import panel as pn

TITLE = "AMRA — aeroelastic model of a rotor in autorotation"

_INTRO = """
## Dashboard coming soon

AMRA is an open, browser-based aeroelastic simulator for two-bladed teetering
autogyro rotors in autorotation, re-implementing Trchalík, Gillies & Thomson (2008),
*Development of an aeroelastic stability boundary for a rotor in autorotation*.

The interactive dashboard is being built. It will offer:

- sliders for the blade's torsional stiffness **GJ**, axial stiffness **EA**,
  chordwise **CG** position, the **advance ratio** and the model **fidelity**;
- **streaming time histories** of the blade response and rotor speed while a
  simulation runs;
- a **stability boundary map** built from many runs.

Meanwhile the solver can be used from the command line:

```
amra rotor    --preset mccutcheon --json
amra modes    --preset mccutcheon --json
amra trim     --preset mccutcheon --json
amra simulate --preset paper-boundary --gj 100 --json
amra bench
```
"""


def create_app() -> pn.template.FastListTemplate:
    """Build a fresh page for one session."""
    intro = pn.pane.Markdown(_INTRO, sizing_mode="stretch_width", name="intro")
    return pn.template.FastListTemplate(
        title=TITLE,
        main=[intro],
        main_max_width="900px",
    )


if __name__.startswith("bokeh"):
    # Run by ``panel serve app/main.py``: one new page per session.
    create_app().servable()
elif __name__ == "__main__":
    # ``python app/main.py``: same page via a dynamic server.
    pn.serve(create_app, port=5006, address="127.0.0.1", show=False)
