"""Measurement files (design section 5): a CSV (first column t [s], uniform) plus a TOML sidecar.

Sidecar keys: model, sample_rate_hz, [inputs] and [outputs] mapping column -> {unit, model_variable},
optional level, level_value, excitation, notes. Units are converted to SI on reading.
"""
from __future__ import annotations

import pathlib
from dataclasses import dataclass, field

import numpy as np

from .signals import assert_uniform
from .tomlfile import read_toml

TO_SI = {"m": 1.0, "mm": 1e-3, "rad": 1.0, "m/s": 1.0, "m/s2": 1.0, "m/s^2": 1.0, "m/s²": 1.0, "g": 9.80665, "N": 1.0}


class MeasurementError(ValueError):
    """A measurement file that cannot be used; names the file and the field."""


@dataclass
class Channel:
    """One measured column: its unit in the file and the model variable it corresponds to."""

    column: str
    unit: str
    model_variable: str


@dataclass
class Measurement:
    """Signals in SI units on a uniform grid, keyed by column name."""

    path: pathlib.Path
    model: str
    t: np.ndarray
    inputs: dict[str, Channel]
    outputs: dict[str, Channel]
    values: dict[str, np.ndarray]
    level: str = ""
    level_value: float | None = None
    excitation: dict = field(default_factory=dict)
    notes: str = ""

    @property
    def sample_rate_hz(self) -> float:
        return 1.0 / (self.t[1] - self.t[0])

    def by_variable(self, kind: str = "outputs") -> dict[str, np.ndarray]:
        """Signals keyed by model variable name."""
        return {ch.model_variable: self.values[c] for c, ch in getattr(self, kind).items()}


def _channels(path, table, section):
    if not isinstance(table, dict):
        raise MeasurementError(f"{path}: [{section}] must be a table of column = {{unit, model_variable}}")
    out = {}
    for col, spec in table.items():
        if not isinstance(spec, dict) or set(spec) - {"unit", "model_variable"} or "unit" not in spec \
                or "model_variable" not in spec:
            raise MeasurementError(f"{path}: [{section}.{col}] needs exactly unit and model_variable")
        if spec["unit"] not in TO_SI:
            raise MeasurementError(f"{path}: [{section}.{col}.unit] '{spec['unit']}' unknown; "
                                   f"allowed: {', '.join(TO_SI)}")
        out[col] = Channel(col, spec["unit"], spec["model_variable"])
    return out


def read_measurement(csv_path: str | pathlib.Path) -> Measurement:
    """Read one CSV + TOML pair (the sidecar has the same stem); validate and convert to SI."""
    csv_path = pathlib.Path(csv_path)
    side = csv_path.with_suffix(".toml")
    if not csv_path.is_file():
        raise MeasurementError(f"{csv_path}: file not found")
    meta = read_toml(side, MeasurementError)
    allowed = {"model", "sample_rate_hz", "inputs", "outputs", "level", "level_value", "excitation", "notes"}
    extra = set(meta) - allowed
    if extra:
        raise MeasurementError(f"{side}: [{sorted(extra)[0]}] unknown key; allowed: {', '.join(sorted(allowed))}")
    for key in ("model", "sample_rate_hz", "outputs"):
        if key not in meta:
            raise MeasurementError(f"{side}: [{key}] missing")
    inputs = _channels(side, meta.get("inputs", {}), "inputs")
    outputs = _channels(side, meta["outputs"], "outputs")
    with open(csv_path, encoding="utf-8") as f:
        header = [h.strip().strip('"') for h in f.readline().strip().split(",")]
    if not header or header[0] != "t":
        raise MeasurementError(f"{csv_path}: first column must be 't' [s], found '{header[0] if header else ''}'")
    try:
        data = np.loadtxt(csv_path, delimiter=",", skiprows=1, ndmin=2)
    except ValueError as exc:
        raise MeasurementError(f"{csv_path}: not a numeric CSV: {exc}") from exc
    if data.shape[1] != len(header):
        raise MeasurementError(f"{csv_path}: {len(header)} column names but {data.shape[1]} columns of numbers")
    cols = dict(zip(header, data.T))
    t = cols.pop("t")
    try:
        dt = assert_uniform(t)
    except ValueError as exc:
        raise MeasurementError(f"{csv_path}: column 't': {exc}") from exc
    fs = float(meta["sample_rate_hz"])
    if abs(1 / dt - fs) > 1e-6 * fs:
        raise MeasurementError(f"{side}: [sample_rate_hz] = {fs} but column 't' is sampled at {1 / dt:.9g} Hz")
    values = {}
    for name, ch in {**inputs, **outputs}.items():
        if name not in cols:
            raise MeasurementError(f"{csv_path}: column '{name}' named in {side.name} is missing; "
                                   f"columns: {', '.join(header)}")
        v = cols[name]
        bad = np.flatnonzero(~np.isfinite(v))
        if bad.size:
            raise MeasurementError(f"{csv_path}: column '{name}' has {bad.size} non-finite value(s), first at "
                                   f"t = {t[bad[0]]:g} s")
        values[name] = v * TO_SI[ch.unit]
    lv = meta.get("level_value")
    return Measurement(csv_path, str(meta["model"]), t, inputs, outputs, values, str(meta.get("level", "")),
                       None if lv is None else float(lv), dict(meta.get("excitation", {})), str(meta.get("notes", "")))


def _toml_value(v) -> str:
    """A scalar as TOML: quoted string, true/false, or number."""
    if isinstance(v, str):
        return f'"{v}"'
    if isinstance(v, bool):
        return "true" if v else "false"
    return f"{v}"


def write_measurement(csv_path: str | pathlib.Path, model: str, t: np.ndarray, inputs: dict[str, tuple],
                      outputs: dict[str, tuple], level: str = "", level_value: float | None = None,
                      excitation: dict | None = None, notes: str = "") -> pathlib.Path:
    """Write a CSV + TOML pair. inputs/outputs: column -> (samples in SI, unit, model_variable)."""
    csv_path = pathlib.Path(csv_path)
    csv_path.parent.mkdir(parents=True, exist_ok=True)
    dt = assert_uniform(t)
    cols = {**inputs, **outputs}
    data = np.column_stack([t] + [np.asarray(v[0]) / TO_SI[v[1]] for v in cols.values()])
    np.savetxt(csv_path, data, delimiter=",", header=",".join(["t"] + list(cols)), comments="",
               fmt=["%.15g"] + ["%.10g"] * len(cols))  # time with full precision: uniform to 1e-9 over long records

    def table(name, d):
        lines = [f"[{name}]"]
        for c, (_, unit, var) in d.items():
            lines.append(f'{c} = {{ unit = "{unit}", model_variable = "{var}" }}')
        return lines

    lines = [f'model = "{model}"', f"sample_rate_hz = {1 / dt:.12g}"]
    if level:
        lines.append(f'level = "{level}"')
    if level_value is not None:
        lines.append(f"level_value = {level_value:.12g}")
    if notes:
        lines.append(f'notes = "{notes}"')
    if inputs:
        lines += table("inputs", inputs)
    lines += table("outputs", outputs)
    if excitation:
        lines.append("[excitation]")
        for k, v in excitation.items():
            lines.append(f"{k} = {_toml_value(v)}")
    csv_path.with_suffix(".toml").write_text("\n".join(lines) + "\n")
    return csv_path


def read_dataset(folder: str | pathlib.Path) -> list[Measurement]:
    """All measurements (CSV + TOML pairs) in a folder, sorted by level_value then name."""
    folder = pathlib.Path(folder)
    if not folder.is_dir():
        raise MeasurementError(f"{folder}: dataset folder not found")
    items = [read_measurement(p) for p in sorted(folder.glob("*.csv"))]
    if not items:
        raise MeasurementError(f"{folder}: no measurement (CSV + TOML) found")
    return sorted(items, key=lambda m: (m.level_value if m.level_value is not None else 0.0, m.path.name))
