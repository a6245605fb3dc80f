"""Parse an uploaded rotor TOML file from memory, with a size cap; every failure is a message."""
from __future__ import annotations

import tomllib

from amra_core.rotor import Rotor, RotorError
from amra_core.rotor_io import rotor_from_dict

MAX_BYTES = 256 * 1024  #: a rotor description is a few kB; anything near this is not one


class UploadError(ValueError):
    """The upload is not a usable rotor file; the message says why, naming the file."""


def parse_rotor_upload(data: bytes | None, filename: str = "upload") -> Rotor:
    """A :class:`Rotor` from the bytes of a TOML rotor file (see ``assets/rotors/*.toml``)."""
    name = filename or "upload"
    if not data:
        raise UploadError(f"rotor file {name!r} is empty")
    if len(data) > MAX_BYTES:
        raise UploadError(f"rotor file {name!r} is {len(data) / 1024:.0f} kB: too large "
                          f"(a rotor description is a few kB; the limit is {MAX_BYTES // 1024} kB)")
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        raise UploadError(f"rotor file {name!r} is not UTF-8 text (expected a TOML rotor description)") from None
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise UploadError(f"rotor file {name!r} is not valid TOML: {exc}") from None
    try:
        return rotor_from_dict(raw)
    except (RotorError, TypeError, ValueError) as exc:
        raise UploadError(f"rotor file {name!r}: {exc}") from None
