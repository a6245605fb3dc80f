"""The dashboard's views: each subscribes to the session events it draws."""
import holoviews as hv

#: the colour of each fidelity, wherever fidelities are compared (map boundaries, ladder)
FIDELITY_COLOURS = {"rigid": "#1565c0", "fem-torsion": "#ef6c00", "fem-coupled": "#6a1b9a"}


class Dim(hv.Dimension):
    """A HoloViews dimension whose axis label writes its unit in brackets ("Frequency [Hz]"), as the
    live plots, the map and the controls do (HoloViews' own default is "Frequency (Hz)")."""

    unit_format = " [{unit}]"


def signed(x: float, digits: int) -> str:
    """``x`` with its sign to ``digits`` decimals; what rounds to zero is +0 ("teeter -0.00°" and a
    "-0" change read as values)."""
    return f"{round(x, digits) + 0.0:+.{digits}f}"
