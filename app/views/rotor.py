"""Watch the mode, not only its traces: the rotor drawn from the solver's state.

:class:`RotorDrawing` is two small Bokeh figures: a **side view** of both blades' out-of-plane
displacement, teeter included, and the hub bar (blade 0 to the right), exaggerated ``FLAP_SCALE``
times: a seesaw rocks, a collective flap cones both blades alike; and each blade's **tip section**
(NACA 0012, chord to scale) turned about its elastic axis by the twist, exaggerated
``TWIST_SCALE`` times, nose to the left. :class:`LiveRotor` draws the run's :class:`app.events.Pose`
news; :class:`ModeAnimation` plays one mode's frames (``amra_core.pose.mode_animation``, computed
in the analysis pool) with a Player: nothing runs while it is paused.
"""
from __future__ import annotations

import math

import numpy as np
import panel as pn
from bokeh.models import ColumnDataSource, Legend, Range1d
from bokeh.plotting import figure

from . import signed

FLAP_SCALE = 3.0  #: flap displacement drawn this many times larger than it is [-] (coning ~0.3 m at the tip)
TWIST_SCALE = 10.0  #: elastic twist drawn this many times larger than it is [-]
BLADE_COLOURS = ("#d62728", "#ff7f0e")  #: blade 0, blade 1 (as the live tip-twist plot)


def naca0012(n: int = 24) -> tuple:
    """Outline of a NACA 0012 section of unit chord, leading edge at x = 0 (closed polygon)."""
    x = 0.5 * (1 - np.cos(np.linspace(0.0, math.pi, n)))
    t = 0.6 * (0.2969 * np.sqrt(x) - 0.1260 * x - 0.3516 * x**2 + 0.2843 * x**3 - 0.1036 * x**4)
    return np.concatenate([x, x[::-1]]), np.concatenate([t, -t[::-1]])


def side_view(pose_r_m, flap_m, teeter_rad: float, flap_scale: float = FLAP_SCALE) -> dict:
    """Line data of the side view: per blade (x [m] along the span, y [m] exaggerated flap), and the
    hub bar between the blades' roots."""
    r = np.asarray(pose_r_m, dtype=float)
    f = np.asarray(flap_m, dtype=float) * flap_scale
    r0 = float(r[0])
    return {"blade0": (np.concatenate([[0.0], r]), np.concatenate([[0.0], f[0]])),
            "blade1": (np.concatenate([[0.0], -r]), np.concatenate([[0.0], f[1]])),
            "hub": ([-r0, r0], [-math.tan(teeter_rad * flap_scale) * r0, math.tan(teeter_rad * flap_scale) * r0])}


def tip_section(twist_rad: float, chord_m: float, x_ea: float, twist_scale: float = TWIST_SCALE) -> tuple:
    """A tip section outline turned nose-up by the exaggerated twist about its elastic axis
    (x: chordwise, leading edge to the left; y: up) [m]."""
    x, y = naca0012()
    x = (x - x_ea) * chord_m
    y = y * chord_m
    a = twist_rad * twist_scale  # nose up = leading edge (x < 0) up
    c, s = math.cos(a), math.sin(a)
    return x * c + y * s, -x * s + y * c


def pose_line(t_s: float, p) -> str:
    """The live rotor's line of numbers for pose ``p`` at ``t_s`` [s]."""
    deg = math.degrees
    return (f"t = {t_s:.2f} s · teeter {signed(deg(p.teeter_rad), 2)}° · tip twist {signed(deg(p.twist_rad[0][-1]), 2)}° / "
            f"{signed(deg(p.twist_rad[1][-1]), 2)}° (blade 0 / 1) · tip flap {signed(100 * p.flap_m[0][-1], 1)} / "
            f"{signed(100 * p.flap_m[1][-1], 1)} cm")


def _legend_row(items: list) -> Legend:
    """A legend in one row above a plot, clear of what it draws."""
    return Legend(items=items, location="top_right", orientation="horizontal", padding=2, margin=0,
                  label_height=14, glyph_height=14, spacing=12)


class RotorDrawing:
    """The two figures and their sources; :meth:`draw` shows one pose (radii, flap and twist of both
    blades [m, rad], teeter [rad])."""

    def __init__(self, radius_m: float = 3.81, chord_m: float = 0.197, x_ea: float = 0.32, title: str = "",
                 flap_scale: float = FLAP_SCALE, twist_scale: float = TWIST_SCALE, scales: tuple | None = None):
        self.chord_m, self.x_ea = chord_m, x_ea
        self.flap_scale, self.twist_scale = flap_scale, twist_scale
        self.blades = [ColumnDataSource({"x": [], "y": []}) for _ in range(2)]
        self.hub = ColumnDataSource({"x": [], "y": []})
        self.sections = [ColumnDataSource({"x": [], "y": []}) for _ in range(2)]
        self._look = (radius_m, title, scales)
        self._figures = None
        self._pose = None  #: the arguments of the last :meth:`draw`

    @property
    def figures(self) -> tuple:
        """The side view and the tip sections, built when first shown."""
        if self._figures is None:
            self._figures = self._build()
            if self._pose is not None:  # the last pose asked for while nothing showed it
                self._draw(*self._pose)
        return self._figures

    def _build(self) -> tuple:
        radius_m, title, scales = self._look
        chord_m, flap_scale, twist_scale = self.chord_m, self.flap_scale, self.twist_scale
        reach = 1.05 * radius_m
        flap_note, twist_note = scales or (f"×{flap_scale:g}", f"×{twist_scale:g}")
        side = figure(title=f"{title}Side view: flap and teeter {flap_note}", height=260,
                      sizing_mode="stretch_width", x_range=Range1d(-reach, reach),
                      y_range=Range1d(-0.25 * reach, 0.55 * reach), tools="save", toolbar_location="right",
                      x_axis_label="Span position, blade 0 to the right [m]",
                      y_axis_label=f"Flap displacement {flap_note} [m]")
        items = [("hub bar", [side.line("x", "y", source=self.hub, line_width=6, color="#455a64")])]
        for b, (src, colour) in enumerate(zip(self.blades, BLADE_COLOURS)):
            items.append((f"blade {b}", [side.line("x", "y", source=src, line_width=4, color=colour)]))
        side.add_layout(_legend_row(items), "above")  # inside (top left) it covered blade 1's outer span
        side.toolbar.logo = None
        c = 0.8 * chord_m
        tips = figure(title=f"Tip sections: twist {twist_note}", height=260, width=360,
                      x_range=Range1d(-c, c), y_range=Range1d(-c, c), match_aspect=True, tools="save",
                      x_axis_label="Chordwise, leading edge left [m]", y_axis_label="Up [m]")
        items = [(f"blade {b}", [tips.patch("x", "y", source=src, fill_alpha=0.25, color=colour, line_width=2)])
                 for b, (src, colour) in enumerate(zip(self.sections, BLADE_COLOURS))]
        tips.add_layout(_legend_row(items), "above")
        tips.toolbar.logo = None
        return side, tips

    def draw(self, r_m, flap_m, twist_rad, teeter_rad: float, chord_m: float | None = None,
             x_ea: float | None = None, radius_m: float | None = None) -> None:
        """One pose; the tip section's chord [m] and elastic axis [chord fraction] and the radius [m]
        are the drawn rotor's (the run's or the mode's), when given. Until the figures are shown, only
        the pose is kept (a run posts ten a second; nobody sees them in a tab never opened)."""
        self._pose = (r_m, flap_m, twist_rad, teeter_rad, chord_m, x_ea, radius_m)
        if self._figures is not None:
            self._draw(*self._pose)

    def _draw(self, r_m, flap_m, twist_rad, teeter_rad, chord_m, x_ea, radius_m) -> None:
        if chord_m is not None and x_ea is not None:
            self.chord_m, self.x_ea = float(chord_m), float(x_ea)
        self._fit(radius_m)
        lines = side_view(r_m, flap_m, teeter_rad, self.flap_scale)
        for b in range(2):
            x, y = lines[f"blade{b}"]
            self.blades[b].data = {"x": x, "y": y}
            sx, sy = tip_section(float(np.asarray(twist_rad)[b][-1]), self.chord_m, self.x_ea, self.twist_scale)
            self.sections[b].data = {"x": sx, "y": sy}
        self.hub.data = {"x": lines["hub"][0], "y": lines["hub"][1]}

    def _fit(self, radius_m: float | None) -> None:
        """Axis ranges for the radius and chord drawn (the figures are made for the defaults)."""
        if radius_m is not None:
            self._look = (float(radius_m),) + self._look[1:]
        if self._figures is None:
            return
        side, tips = self._figures
        reach, c = 1.05 * self._look[0], 0.8 * self.chord_m
        if (side.x_range.end, tips.x_range.end) != (reach, c):
            side.x_range.update(start=-reach, end=reach)
            side.y_range.update(start=-0.25 * reach, end=0.55 * reach)
            tips.x_range.update(start=-c, end=c)
            tips.y_range.update(start=-c, end=c)

    def panel(self) -> pn.Row:
        return pn.Row(pn.pane.Bokeh(self.figures[0], sizing_mode="stretch_width"), pn.pane.Bokeh(self.figures[1]),
                      sizing_mode="stretch_width")


class LiveRotor(pn.viewable.Viewer):
    """The live run's rotor (module docstring); ``poses`` counts the poses drawn."""

    def __init__(self, session, **params):
        super().__init__(**params)
        from ..events import Pose
        self.drawing = RotorDrawing(title="Live rotor. ")
        self.poses = 0
        self.info = pn.pane.Markdown("The rotor as the run computes it: press *Run*.", name="rotor-info")
        session.subscribe(Pose, self.show)

    def show(self, ev) -> None:
        p = ev.pose
        self.poses += 1
        self.drawing.draw(p.r_m, p.flap_m, p.twist_rad, p.teeter_rad, p.chord_m, p.x_ea, p.radius_m)
        self.info.object = pose_line(ev.t_s, p)

    def __panel__(self):
        return pn.Column(self.info, self.drawing.panel(), sizing_mode="stretch_width", name="live-rotor")


class ModeAnimation(pn.viewable.Viewer):
    """One mode's shape through a cycle, played frame by frame (module docstring)."""

    def __init__(self, **params):
        super().__init__(**params)
        self.drawing = RotorDrawing(title="Mode. ", flap_scale=1.0, twist_scale=1.0,
                                    scales=("not to scale", "not to scale"))
        self.frames = None
        self.player = pn.widgets.Player(start=0, end=23, value=0, loop_policy="loop", interval=80, label="Phase",
                                        show_loop_controls=False, visible=False, css_classes=["amra-mode-player"])
        self.info = pn.pane.Markdown("Pick a mode to watch its shape.", name="mode-anim-info")
        self.player.param.watch(lambda e: self.show_frame(e.new), "value")

    def load(self, result: dict) -> None:
        """Frames from :func:`app.compute.mode_frames` (or an ``error``)."""
        if result.get("error"):
            self.frames = None
            self.player.visible = False
            self.info.object = f"No animation: {result['error']}"
            return
        self.frames = result
        n = len(result["flap"])
        self.player.param.update(end=n - 1, value=0, visible=True)
        self.show_frame(0)
        self.info.object = result["text"]

    def show_frame(self, k: int) -> None:
        if self.frames is None:
            return
        f = self.frames
        k = int(k) % len(f["flap"])
        self.drawing.draw(f["r_m"], f["flap"][k], f["twist"][k], f["teeter"][k], f.get("chord_m"), f.get("x_ea"),
                          f.get("radius_m"))

    def __panel__(self):
        return pn.Column(self.info, self.player, self.drawing.panel(), sizing_mode="stretch_width",
                         name="mode-animation")
