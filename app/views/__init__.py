"""The dashboard's views: each subscribes to the session events it draws."""

#: the colour of each fidelity, wherever fidelities are compared (map boundaries, ladder)
FIDELITY_COLOURS = {"rigid": "#1565c0", "fem-torsion": "#ef6c00", "fem-coupled": "#6a1b9a"}
