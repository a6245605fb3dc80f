"""Fixtures shared by the solver tests: the shipped presets, loaded once per session."""
import pytest

from amra_core.rotor_io import load_preset


@pytest.fixture(scope="session")
def mccutcheon():
    return load_preset("mccutcheon")


@pytest.fixture(scope="session")
def paper():
    return load_preset("paper-boundary")
