"""A dataset as the diagnosis reads it: the measurement files checked against the FMU's variables and units,
brought to one analysis rate, made into records and split into calibration and held-out files."""
from __future__ import annotations

import hashlib
import pathlib
from dataclasses import dataclass

from pyfit.analysis.signals import clipped_samples
from pyfit.gap import localise
from pyfit.gap import simulate as sim
from pyfit.gap.config import DiagnoseConfig, DiagnoseError
from pyfit.gap.rate import AnalysisRate, analysis_rate, at_rate, common_rate
from pyfit.io.data import MeasurementError, check_quantities, read_dataset_with_order


@dataclass(frozen=True)
class Dataset:
    """A dataset as the diagnosis reads it (load)."""

    records: list  # every record, in level order (pyfit.gap.simulate.Record)
    cal: list  # the records calibrated on
    held: list  # the records held out
    key: str  # the data's digest
    order: str  # what the level order rests on (pyfit.io.data.level_order)
    aside: dict  # records the default split set aside (localise.unsettled: name -> period scatter, lower floor)
    voltages: list  # 'column (model_variable)' of each channel recorded as a voltage (System.gains_free)
    rate: AnalysisRate  # the rate the records are analysed at (the files' or decimated: pyfit.gap.rate)
    recorded_hz: dict  # name -> the rate a file was recorded at, where it was faster than the dataset's
    # (rate.common_rate: decimated to the slowest file's rate)
    measurements: list  # the files as read, in level order (pyfit.io.data.Measurement: columns, units, SI values)
    clipped: dict  # 'file column' -> samples held at the column's extreme by a range limit (signals.clipped_samples)


def default_calibration(records: list) -> list:
    """The records calibrated on by default (`records` ordered by level): of three levels or more, every file of
    the lowest and of the highest level (the levels between are held out: more levels hold more out, not more into
    every fit's simulations); of two, every file of the lower (the higher is held out); of one, every other file
    from the first (a dataset of one level in several files, e.g. a stepped sine's frequencies: the calibration
    spans them), the first alone of two files."""
    levels = sorted({r.level_value for r in records})
    if len(levels) >= 3:
        return [r for r in records if r.level_value in (levels[0], levels[-1])]
    if len(levels) == 2:
        return [r for r in records if r.level_value == levels[0]]
    return records[::2] if len(records) >= 3 else records[:1]


def _measurements(data_dir: pathlib.Path, system, units: dict) -> tuple[list, str, set]:
    """The dataset's files as read, what their level order rests on, and the channels recorded as voltages."""
    try:
        ms, order = read_dataset_with_order(data_dir)
    except MeasurementError as exc:
        raise DiagnoseError(str(exc)) from exc
    if len(ms) < 2:
        raise DiagnoseError(f"{data_dir}: a diagnosis needs at least two files (one to calibrate on, one held "
                            f"out); found {len(ms)}")
    voltages = set()
    for m in ms:
        if m.model != system.fmu:
            raise DiagnoseError(f"{m.path.with_suffix('.toml')}: model = '{m.model}' but --model {system.name} "
                                f"expects '{system.fmu}'")
        try:
            voltages.update(check_quantities(m, units, system.gains_free))
        except MeasurementError as exc:
            raise DiagnoseError(str(exc)) from exc
    return list(ms), order, voltages


def _records(ms: list, system, cfg: DiagnoseConfig, md_vars) -> list:
    """The records of the files (at the analysis rate), each input and output a variable of the FMU."""
    variables = {v.name for v in md_vars}
    try:
        records = [sim.record_of(m, system.motion_inputs, cfg.transient_s, system.smooth_inputs) for m in ms]
    except ValueError as exc:
        raise DiagnoseError(str(exc)) from exc
    for m, r in zip(ms, records):
        for kind, names in (("inputs", r.inputs), ("outputs", r.outputs)):
            bad = [n for n in names if n not in variables]
            if bad:
                causality = kind[:-1]
                allowed = sorted(v.name for v in md_vars if v.causality == causality)
                raise DiagnoseError(f"{m.path.with_suffix('.toml')}: [{kind}] model_variable '{bad[0]}' is not a "
                                    f"variable of {system.fmu}; allowed: {', '.join(allowed)}")
    return records


def _split(records: list, cfg: DiagnoseConfig, data_dir) -> tuple[list, list, dict]:
    """The calibration and held-out records, and those the default split set aside: a record whose response does
    not repeat between periods (no steady state: a simulation cannot follow it sample by sample, and calibrating on
    it pulls every parameter off)."""
    names = [r.name for r in records]
    aside = {} if cfg.calibration else localise.unsettled(records)
    if len(records) - len(aside) < 2:
        raise DiagnoseError(f"{data_dir}: the response of {', '.join(aside)} does not repeat from one period to the "
                            "next (no steady state), which leaves fewer than two files to calibrate on and hold "
                            "out; allowed: name the files to calibrate on in [diagnose] calibration to use them all")
    records = [r for r in records if r.name not in aside]
    if cfg.calibration:
        bad = [c for c in cfg.calibration if c not in names]
        if bad:
            raise DiagnoseError(f"calibration: no file '{bad[0]}' in {data_dir}; files: {', '.join(names)}")
        cal = [r for r in records if r.name in cfg.calibration]
    else:
        cal = default_calibration(records)
    held = [r for r in records if r not in cal]
    if not held or not cal:
        raise DiagnoseError(f"calibration: the split leaves {'no held-out' if not held else 'no calibration'} file")
    return cal, held, aside


def load(data_dir, system, cfg: DiagnoseConfig, runner) -> Dataset:
    """Records of the dataset, validated against the FMU's variables and their units, split into calibration
    and held-out."""
    data_dir = pathlib.Path(data_dir)
    md_vars = runner.model_description.modelVariables
    read, order, voltages = _measurements(data_dir, system, {v.name: v.unit or "" for v in md_vars})
    try:
        ms, recorded_hz = common_rate(read)
    except ValueError as exc:
        raise DiagnoseError(str(exc)) from exc
    rate = analysis_rate(ms)
    ms = [at_rate(m, rate.factor) for m in ms]
    unknown = [e for e in (cfg.effects or []) if e not in system.effects]
    if unknown:
        raise DiagnoseError(f"effects: '{unknown[0]}' unknown for {system.name}; allowed: "
                            f"{', '.join(system.effects)}")
    records = _records(ms, system, cfg, md_vars)
    cal, held, aside = _split(records, cfg, data_dir)
    digest = hashlib.sha256(str(rate.factor).encode())
    for m in ms:
        digest.update(m.path.read_bytes())
        digest.update(m.path.with_suffix(".toml").read_bytes())
    clipped = {f"{m.name} {col}": n for m in read for col, v in m.values.items() if (n := clipped_samples(v))}
    return Dataset([r for r in records if r.name not in aside], cal, held, digest.hexdigest()[:16], order, aside,
                   sorted(voltages), rate, recorded_hz, read, clipped)
