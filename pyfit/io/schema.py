"""The one TOML schema layer: every input file (study, fit, diagnosis, nominal model, measurement sidecar)
is read and checked here, and every error has one format:

    FILE: [SECTION.KEY] PROBLEM; allowed: WHAT IS ALLOWED
"""
from __future__ import annotations

import codecs
import pathlib
import tomllib
from typing import NoReturn


class ConfigError(ValueError):
    """An input file that cannot be used; the message names file, key and the allowed values."""


def fail(path, key: str, problem: str, allowed=None, error: type[ConfigError] = ConfigError) -> NoReturn:
    """Raise `error` in the one format: 'FILE: [KEY] PROBLEM; allowed: ALLOWED'."""
    msg = f"{path}: [{key}] {problem}"
    if allowed is not None:
        msg += f"; allowed: {allowed}"
    raise error(msg)


BOMS = ((codecs.BOM_UTF32_LE, "utf-32"), (codecs.BOM_UTF32_BE, "utf-32"), (codecs.BOM_UTF8, "utf-8-sig"),
        (codecs.BOM_UTF16_LE, "utf-16"), (codecs.BOM_UTF16_BE, "utf-16"))
TEXT_ALLOWED = "UTF-8 text (with or without a byte-order mark) or UTF-16/UTF-32 with a byte-order mark"


def read_text(path, error: type[ConfigError] = ConfigError) -> str:
    """A text file decoded by its byte-order mark (UTF-8, UTF-16, UTF-32), else as UTF-8; a binary or
    undecodable file raises `error` naming the file, the byte offset and what is allowed."""
    path = pathlib.Path(path)
    if not path.is_file():
        raise error(f"{path}: file not found")
    raw = path.read_bytes()
    encoding = next((enc for bom, enc in BOMS if raw.startswith(bom)), None)
    nul = raw.find(b"\x00")
    if encoding in (None, "utf-8-sig") and nul >= 0:
        raise error(f"{path}: a binary file (NUL byte at offset {nul}); allowed: {TEXT_ALLOWED}")
    try:
        return raw.decode(encoding or "utf-8")
    except UnicodeDecodeError as exc:
        raise error(f"{path}: not {encoding or 'UTF-8'} text (byte offset {exc.start}: {exc.reason}); "
                    f"allowed: {TEXT_ALLOWED}") from None


def read_toml(path, error: type[ConfigError] = ConfigError) -> dict:
    """The parsed file; `error` names the file when it is missing, not text or not valid TOML."""
    text = read_text(path, error)
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise error(f"{path}: not valid TOML: {exc}") from exc


def check_sections(doc: dict, path, allowed, required=(), error: type[ConfigError] = ConfigError) -> None:
    """Top-level tables: none unknown, none of `required` missing."""
    extra = set(doc) - set(allowed)
    if extra:
        fail(path, sorted(extra)[0], "unknown section", ", ".join(sorted(allowed)), error)
    for s in required:
        if s not in doc:
            fail(path, s, "missing section", error=error)


def _is_number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def check_table(table: dict, path, section: str, spec: dict, error: type[ConfigError] = ConfigError) -> dict:
    """Check a TOML table against spec {key: (type, required, default)}; return the values with defaults.

    type: a Python type (int and float accept whole numbers; float converts them), "number" (int or float,
    returned as float), "floats" (list of numbers), "strings" (a string or a list of strings), None (any value:
    the caller checks it)."""
    if not isinstance(table, dict):
        fail(path, section or "file", f"must be a table, not {table!r}", error=error)
    unknown = set(table) - set(spec)
    if unknown:
        fail(path, f"{section}.{sorted(unknown)[0]}".lstrip("."), "unknown key", ", ".join(sorted(spec)), error)
    out = {}
    for key, (typ, required, default) in spec.items():
        where = f"{section}.{key}".lstrip(".")
        if key not in table:
            if required:
                fail(path, where, "missing", error=error)
            out[key] = default
            continue
        value = table[key]
        if typ in (float, "number"):
            if not _is_number(value):
                fail(path, where, f"must be a number, not {value!r}", error=error)
            value = float(value)
        elif typ == "floats":
            if not isinstance(value, list) or not all(_is_number(v) for v in value):
                fail(path, where, f"must be a list of numbers, not {value!r}", error=error)
            value = [float(v) for v in value]
        elif typ == "strings":
            if isinstance(value, str):
                value = [value]
            if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
                fail(path, where, f"must be a string or a list of strings, not {value!r}", error=error)
        elif typ is int:
            if not isinstance(value, int) or isinstance(value, bool):
                fail(path, where, f"must be a whole number, not {value!r}", error=error)
        elif typ is not None and not isinstance(value, typ):
            fail(path, where, f"must be {typ.__name__}, not {value!r}", error=error)
        out[key] = value
    return out


def check_numbers(table: dict, path, section: str, error: type[ConfigError] = ConfigError) -> dict[str, float]:
    """A table of name = number, as floats."""
    if not isinstance(table, dict):
        fail(path, section, f"must be a table of name = number, not {table!r}", error=error)
    for k, v in table.items():
        if not _is_number(v):
            fail(path, f"{section}.{k}", f"must be a number, not {v!r}", error=error)
    return {k: float(v) for k, v in table.items()}


def check_bounds(value, path, key: str, error: type[ConfigError] = ConfigError) -> tuple[float, float]:
    """[lower, upper] with lower < upper."""
    if not (isinstance(value, list) and len(value) == 2 and all(_is_number(v) for v in value)):
        fail(path, key, f"{value!r} is not [lower, upper]", error=error)
    if not value[0] < value[1]:
        fail(path, key, f"inverted or empty bounds {value}", "lower < upper", error)
    return float(value[0]), float(value[1])
