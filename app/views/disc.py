"""Classroom view: the rotor disc seen from above over the last revolution (paper Figs 4, 8, 9).

Blade 0's torque per unit span [N m/m], elastic twist [deg] and flap displacement [mm] at every
recorded azimuth and station of the last revolution, drawn in polar form (x = r cos ψ,
y = r sin ψ) as a curvilinear mesh. From ``Simulation.spanwise_last_revolution``.
"""
from __future__ import annotations

import math

import holoviews as hv
import numpy as np
import panel as pn
from holoviews.streams import Pipe

from ..events import Disc
from . import Dim

X_DIM = Dim("x_m", label="x = r cos ψ", unit="m")
Y_DIM = Dim("y_m", label="y = r sin ψ", unit="m")
FIELDS = (("torque_per_length_nm_m", "Torque per span", "N m/m", 1.0, "RdBu_r"),
          ("twist_rad", "Elastic twist", "deg", 180.0 / math.pi, "PuOr_r"),
          ("flap_m", "Flap displacement", "mm", 1000.0, "viridis"))


def disc_mesh(data: dict, field: str, scale: float):
    """(X, Y, Z) arrays (n_azimuth + 1, n_stations) closed around the disc, or None."""
    if not data or field not in data:
        return None
    psi = np.asarray(data["azimuth_rad"])
    r = np.asarray(data["r_m"])
    z = np.asarray(data[field]) * scale
    order = np.argsort(psi)
    psi, z = psi[order], z[order]
    psi = np.append(psi, psi[0] + 2 * math.pi)
    z = np.vstack([z, z[:1]])
    P, R = np.meshgrid(psi, r, indexing="ij")
    return R * np.cos(P), R * np.sin(P), z


class DiscView(pn.viewable.Viewer):
    def __init__(self, session, **params):
        super().__init__(**params)
        self.pipe = Pipe(data={})
        session.subscribe(Disc, lambda ev: self.pipe.send(ev.data))

    def _plot(self, data, field, title, unit, scale, cmap):
        mesh = disc_mesh(data, field, scale)
        vdim = Dim(field, label=title, unit=unit)
        if mesh is None:
            qm = hv.QuadMesh((np.zeros((2, 2)), np.zeros((2, 2)), np.full((2, 2), np.nan)), [X_DIM, Y_DIM], vdim)
        else:
            qm = hv.QuadMesh(mesh, [X_DIM, Y_DIM], vdim)
        if mesh is not None and field != "flap_m":
            lim = float(np.nanmax(np.abs(mesh[2]))) or 1.0
            qm = qm.redim.range(**{field: (-lim, lim)})
        return qm.opts(cmap=cmap, colorbar=True, clabel=f"{title} [{unit}]", title=f"{title} [{unit}], last revolution",
                       data_aspect=1, frame_width=260, frame_height=260, tools=["hover"], framewise=True,
                       xlim=(-4, 4), ylim=(-4, 4))

    def __panel__(self):
        plots = [pn.pane.HoloViews(hv.DynamicMap(lambda data, a=a: self._plot(data, *a), streams=[self.pipe]))
                 for a in FIELDS]
        note = pn.pane.Markdown("Rotor disc from above, rotation anticlockwise; ψ = 0 downstream (tail). "
                                "Blade 0 is drawn; blade 1 is half a revolution behind it. Updated each second "
                                "of a run.")
        return pn.Column(note, pn.FlexBox(*plots), sizing_mode="stretch_width")
