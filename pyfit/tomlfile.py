"""Reading a TOML file with one clear error naming the file."""
from __future__ import annotations

import pathlib
import tomllib


def read_toml(path: pathlib.Path, error: type[Exception]) -> dict:
    """The parsed file; `error` names the file when it is missing or not valid TOML."""
    if not path.is_file():
        raise error(f"{path}: file not found")
    try:
        return tomllib.loads(path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as exc:
        raise error(f"{path}: not valid TOML: {exc}") from exc
