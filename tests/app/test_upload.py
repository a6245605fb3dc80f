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


@pytest.mark.parametrize("data, match", [
    (b"a = " + b"[" * 5000 + b"]" * 5000, "nested deeper than"),  # made the parser raise RecursionError
    (b"a" + b".a" * 20000 + b" = 1", "dotted key of more than"),  # cost the parser 1.7 GB and 5 s (40 kB)
])
def test_uploads_the_parser_cannot_take_are_refused_before_parsing(monkeypatch, data, match):
    import tomllib

    def never(*_a, **_k):
        raise AssertionError("the TOML parser was reached")
    monkeypatch.setattr(tomllib, "loads", never)
    with pytest.raises(UploadError, match=match) as info:
        parse_rotor_upload(data, "hostile.toml")
    assert "'hostile.toml'" in str(info.value)


def test_an_upload_and_a_file_are_read_alike(tmp_path):
    """One reader for both: the same text gives the same rotor, the same bad text the same complaint."""
    from amra_core.rotor import RotorError
    from amra_core.rotor_io import load_rotor_file
    text = (ROTORS / "mccutcheon.toml").read_text()
    (tmp_path / "r.toml").write_text(text)
    assert parse_rotor_upload(text.encode(), "r.toml") == load_rotor_file(tmp_path / "r.toml")
    bad = "a = " + "{" * 40 + "}" * 40
    (tmp_path / "bad.toml").write_text(bad)
    with pytest.raises(RotorError, match="nested deeper than 32 levels") as from_file:
        load_rotor_file(tmp_path / "bad.toml")
    with pytest.raises(UploadError, match="nested deeper than 32 levels") as from_upload:
        parse_rotor_upload(bad.encode(), "bad.toml")
    assert str(from_file.value).split(": ", 1)[1] == str(from_upload.value).split(": ", 1)[1]
