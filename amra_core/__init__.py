"""AMRA core: an aeroelastic solver for a two-bladed teetering rotor in autorotation.

Layers (one path for data):
rotor description (``rotor``, TOML presets) -> compiled flat arrays (``model``)
-> jitted kernels (``kernels``) -> chunked ``Simulation`` -> results/verdicts
-> consumers (CLI, map engine, dashboard).
"""
__version__ = "0.1.0"
