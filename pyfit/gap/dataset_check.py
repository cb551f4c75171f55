"""What a diagnosis would read, before it fits anything (`stockbridge diagnose --check`): every file's level,
length and excited band, each column's unit and what it stands for in the model, its RMS in SI units, the noise
floor the data give, the calibration split, the analysis rate and the nominal model's resonances against the
excited band. A user sees in seconds whether the reader took the files as they were meant (units, signs,
levels), where a diagnosis takes minutes."""
from __future__ import annotations

import pathlib
from dataclasses import dataclass

import numpy as np

from pyfit.gap import localise
from pyfit.gap.diagnose import DiagnoseConfig, prepare
from pyfit.gap.report import clipped_lines
from pyfit.io.data import TO_SI


@dataclass(frozen=True)
class ChannelCheck:
    """One used column: what the file holds and what the model reads."""

    column: str
    side: str  # "input" or "output"
    unit: str  # the file's unit (a sensor's voltage: 'mV (100 mV/g)')
    model_variable: str
    model_unit: str  # the FMU's unit of that variable
    rms_si: float  # RMS of the column about its mean, in the model's unit
    inverted: bool
    clipped: int  # samples held at the column's extreme by a range limit (the diagnosis's Dataset.clipped)


@dataclass(frozen=True)
class FileCheck:
    """One measurement file of the dataset."""

    name: str
    level: str
    level_value: float
    duration_s: float
    role: str  # "calibration", "held out" or "set aside" (no steady state)
    excited_hz: tuple[float, float] | None  # None: set aside
    noise_nrmse: float | None  # the noise floor the data give (over its outputs), None: set aside
    noise_method: str
    channels: list[ChannelCheck]


@dataclass(frozen=True)
class DatasetCheck:
    """A dataset as the diagnosis would read it."""

    folder: str
    model: str
    fmu: str
    level_order: str
    file_hz: float
    analysis_hz: float
    files: list[FileCheck]
    excited_hz: tuple[float, float]
    resonances_hz: list[float]  # the nominal start's linear modes
    nominal: dict[str, float]  # the described values (SI) over the FMU's defaults, of the parameters named
    voltage_channels: list[str]
    recorded_hz: dict[str, float]  # files recorded faster than the dataset's rate, decimated to it: name -> Hz


def check_dataset(model: str, data_dir, nominal=None, cfg: DiagnoseConfig | None = None, fmu_dir="fmus",
                  candidates=None) -> DatasetCheck:
    """Read and check a dataset as `diagnose` does (pyfit.gap.diagnose.prepare: the same errors), and summarise
    what was read; nothing is fitted."""
    p = prepare(model, data_dir, cfg or DiagnoseConfig(), fmu_dir, nominal, candidates)
    try:
        units = {v.name: v.unit or "" for v in p.runner.model_description.modelVariables}
        measurements = {m.name: m for m in p.data.measurements}
        roles = {**{r.name: "calibration" for r in p.data.cal}, **{r.name: "held out" for r in p.data.held},
                 **{name: "set aside" for name in p.data.aside}}
        noise = localise.noise_estimates(p.data.records)
        records = {r.name: r for r in p.data.records}
        files = []
        for name, m in measurements.items():
            channels = []
            for side, table in (("input", m.inputs), ("output", m.outputs)):
                for col, ch in table.items():
                    unit = ch.unit if ch.volts_per_unit is None else \
                        f"{ch.unit} ({ch.volts_per_unit / TO_SI[ch.unit]:g} {ch.unit}/{ch.measures})"
                    v = m.values[col]
                    channels.append(ChannelCheck(col, side, unit, ch.model_variable, units.get(ch.model_variable, ""),
                                                 float(np.sqrt(np.mean((v - np.mean(v)) ** 2))), ch.invert,
                                                 p.data.clipped.get(f"{name} {col}", 0)))
            rec = records.get(name)
            length = float(m.t[-1] - m.t[0] + 1 / m.sample_rate_hz)
            files.append(FileCheck(name, m.level, float(m.level_value), length, roles.get(name, "set aside"),
                                   localise.excited_band(rec) if rec else None, noise[name][0] if rec else None,
                                   noise[name][1] if rec else "", channels))
        named = p.described.parameters() if p.described else {}
        return DatasetCheck(str(data_dir), model, pathlib.Path(p.fmu).name, p.data.order, p.data.rate.file_hz,
                            p.data.rate.hz, files, p.band, [m.f_n for m in p.modes], named, p.data.voltages,
                            p.data.recorded_hz)
    finally:
        p.runner.close()


def check_text(c: DatasetCheck) -> str:
    """The check as Markdown: the files, their channels, the split, the noise floor, the band and resonances."""
    resonances = ", ".join(f"{f:.3g}" for f in c.resonances_hz) or "none"
    lines = [f"# Dataset check: {c.folder} ({c.model}, {c.fmu})", "",
             f"{len(c.files)} files, levels ordered by {c.level_order}; sampled at {c.file_hz:g} Hz, analysed at "
             f"{c.analysis_hz:g} Hz. Excited band {c.excited_hz[0]:.3g}-{c.excited_hz[1]:.3g} Hz; the nominal "
             f"model's resonances (at its start values): {resonances} Hz.", "",
             "| file | level | length [s] | role | excited [Hz] | noise floor (NRMSE) |", "|---|---|---|---|---|---|"]
    for f in c.files:
        band = f"{f.excited_hz[0]:.3g}-{f.excited_hz[1]:.3g}" if f.excited_hz else "—"
        floor = f"{f.noise_nrmse:.2g} ({f.noise_method})" if f.noise_nrmse is not None else "—"
        lines.append(f"| {f.name} | {f.level or f'{f.level_value:g}'} | {f.duration_s:.4g} | {f.role} | {band} | "
                     f"{floor} |")
    lines += ["", "| file | column | side | unit in the file | model variable [unit] | RMS in the model's unit | "
                  "sign |", "|---|---|---|---|---|---|---|"]
    for f in c.files:
        for ch in f.channels:
            sign = "inverted" if ch.inverted else "as recorded"
            lines.append(f"| {f.name} | {ch.column} | {ch.side} | {ch.unit} | {ch.model_variable} "
                         f"[{ch.model_unit or '—'}] | {ch.rms_si:.4g} | {sign} |")
    clipped = {f"{f.name} {ch.column}": ch.clipped for f in c.files for ch in f.channels if ch.clipped}
    if clipped:
        lines += ["", clipped_lines(clipped)[0]]
    if c.recorded_hz:
        lines += ["", f"Recorded faster and decimated to the dataset's {c.file_hz:g} Hz: "
                  + ", ".join(f"{name} ({hz:g} Hz)" for name, hz in c.recorded_hz.items()) + "."]
    if c.voltage_channels:
        lines += ["", "Recorded as voltages with an unknown gain (every parameter the model fits carries it): "
                  + ", ".join(c.voltage_channels) + "."]
    if c.nominal:
        lines += ["", "Described nominal (SI): " + ", ".join(f"{k} = {v:.6g}" for k, v in c.nominal.items()) + "."]
    return "\n".join(lines) + "\n"
