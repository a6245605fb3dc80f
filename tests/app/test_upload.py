"""Rotor files uploaded from the browser: parsed from memory with a size cap, every failure a message."""
from __future__ import annotations

from pathlib import Path

import pytest

from app.controls import MAX_BYTES, UploadError, parse_rotor_upload

ROTORS = Path(__file__).resolve().parents[2] / "assets" / "rotors"


def test_a_shipped_rotor_file_parses():
    r = parse_rotor_upload((ROTORS / "mccutcheon.toml").read_bytes(), "mine.toml")
    assert r.name == "mccutcheon" and r.radius_m == pytest.approx(3.81)


@pytest.mark.parametrize("data, match", [
    (b"", "is empty"),
    (b"name = [unclosed", "not valid TOML"),
    (b"\xff\xfe\x00garbage", "not UTF-8"),
    (b"name = 'x'\nradius_m = 3.0\n", "blade"),
    (b"x" * (MAX_BYTES + 1), "too large"),
])
def test_broken_files_give_a_message_naming_the_file(data, match):
    with pytest.raises(UploadError, match=match) as info:
        parse_rotor_upload(data, "bad.toml")
    assert "'bad.toml'" in str(info.value)


def test_out_of_range_value_in_the_file_is_named():
    text = (ROTORS / "mccutcheon.toml").read_text().replace("radius_m = 3.81", "radius_m = -1.0")
    with pytest.raises(UploadError, match="radius_m"):
        parse_rotor_upload(text.encode(), "neg.toml")
