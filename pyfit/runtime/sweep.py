"""Sweep studies: models x parameter sets x excitation levels (x sine frequencies), run as one batch,
written as CSV files and figures (loops, time histories, PSDs, spectrogram, instantaneous frequency)."""
from __future__ import annotations

import csv
import pathlib
from dataclasses import dataclass

import numpy as np
from fmpy import read_model_description

from pyfit.report import plots
from pyfit.analysis import signals
from pyfit.runtime.batch import RunSpec, run_batch
from pyfit.io.sweep_config import SweepConfig
from pyfit.analysis.excitation import Excitation
from pyfit.runtime.examples import ensure_fmu

# (force, displacement, velocity) whose loop and power characterise each model
LOOP_SIGNALS = {"SDOFBoucWen": ("F", "y", "v"), "StockbridgeDamper": ("F_clamp", "x_clamp", "v_clamp")}
for _c in "abcd":
    LOOP_SIGNALS[f"TwoDOF{_c}"] = ("F", "y1", "v1")


@dataclass
class FmuInterface:
    """Names an FMU accepts: settable parameters, all variables, and its outputs in order."""

    parameters: set
    variables: set
    outputs: list
    units: dict


def fmu_interface(fmu: pathlib.Path) -> FmuInterface:
    md = read_model_description(str(fmu))
    params = {v.name for v in md.modelVariables if v.causality == "parameter"}
    return FmuInterface(params, {v.name for v in md.modelVariables},
                        [v.name for v in md.modelVariables if v.causality == "output"],
                        {v.name: v.unit for v in md.modelVariables})


@dataclass
class PlannedRun:
    """One run of the study and the labels that place it in the tables."""

    label: str
    model: str
    set_name: str
    level: float
    frequency: float | None
    spec: RunSpec


def excitation_of(cfg: SweepConfig, level: float, frequency: float | None) -> Excitation:
    ex = cfg.excitation
    return Excitation(ex.exc_type, level, frequency if frequency is not None else ex.f_start, ex.f_end, ex.rate,
                      ex.octaves_per_minute, ex.t_ramp)


def plan(cfg: SweepConfig, fmu_dir: pathlib.Path) -> list[PlannedRun]:
    """Every run of the study, in a stable order with unique labels."""
    runs = []
    freqs = cfg.excitation.frequencies if cfg.excitation.kind == "sine" else [None]
    for model in cfg.models:
        fmu = ensure_fmu(model, fmu_dir)
        iface = fmu_interface(fmu)
        amp_name = "exc_v0" if cfg.excitation.exc_type >= 4 else "exc_amplitude"
        if amp_name not in iface.parameters:
            raise ValueError(f"{cfg.path}: [excitation.kind] '{cfg.excitation.kind}' drives a displacement; "
                             f"model {model} takes a force (use sine, linear_sweep or log_sweep)")
        outputs = list(dict.fromkeys(cfg.outputs[model] + list(LOOP_SIGNALS[model])))
        for pset in cfg.parameter_sets:
            for level in cfg.excitation.levels:
                for f in freqs:
                    e = excitation_of(cfg, level, f)
                    params = dict(cfg.parameters, **pset.values, exc_type=e.kind, exc_f_start=e.f_start,
                                  exc_f_end=e.f_end, exc_rate=e.rate, exc_octaves_per_minute=e.octaves_per_minute,
                                  exc_t_ramp=e.t_ramp)
                    params[amp_name] = level
                    label = f"{model}_{pset.name}_L{level:g}" + (f"_f{f:g}Hz" if f is not None else "")
                    spec = RunSpec(str(fmu), cfg.stop_time, cfg.output_interval, tuple(outputs), params,
                                   tolerance=cfg.tolerance, label=label)
                    runs.append(PlannedRun(label, model, pset.name, level, f, spec))
    return runs


def run_study(cfg: SweepConfig, fmu_dir: pathlib.Path, out_dir: pathlib.Path, workers: int | None = None,
              scheduler: str | None = None, progress: bool = True) -> list[dict]:
    """Run the study; write runs/<label>.csv, summary.csv and the figures; return the summary rows."""
    runs = plan(cfg, fmu_dir)
    results = run_batch([r.spec for r in runs], workers=workers, scheduler=scheduler, progress=progress,
                        desc=cfg.path.stem)
    (out_dir / "runs").mkdir(parents=True, exist_ok=True)
    rows = []
    for run, res in zip(runs, results):
        row = {"label": run.label, "model": run.model, "parameter_set": run.set_name, "level": run.level,
               "frequency_hz": "" if run.frequency is None else run.frequency, "ok": res.ok, "message": res.message}
        if res.ok:
            names = list(run.spec.outputs)
            np.savetxt(out_dir / "runs" / f"{run.label}.csv", np.column_stack([res.time] + [res[n] for n in names]),
                       delimiter=",", header=",".join(["t"] + names), comments="")
            for n in names:
                row[f"max_abs_{n}"] = float(np.max(np.abs(res[n])))
            if run.frequency is not None:
                force, disp, vel = LOOP_SIGNALS[run.model]
                try:
                    cyc = signals.steady_cycle(res.time, res[force], res[vel], res[disp], run.frequency)
                    row.update(loop_energy_j=cyc.dissipated_energy, mean_power_w=cyc.mean_power,
                               impedance_ns_per_m=cyc.impedance)
                except ValueError as exc:  # a period that is not a whole number of samples
                    row["message"] = str(exc)
        rows.append(row)
    _write_summary(out_dir / "summary.csv", rows)
    _figures(cfg, runs, results, out_dir)
    return rows


def _write_summary(path, rows):
    keys = list(dict.fromkeys(k for r in rows for k in r))
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys)
        w.writeheader()
        w.writerows(rows)


def _figures(cfg: SweepConfig, runs: list[PlannedRun], results, out_dir: pathlib.Path):
    title = cfg.title or cfg.path.stem
    for model in cfg.models:
        mine = [(r, res) for r, res in zip(runs, results) if r.model == model and res.ok]
        if not mine:
            continue
        units = fmu_interface(pathlib.Path(mine[0][0].spec.fmu)).units
        force, disp, _ = LOOP_SIGNALS[model]
        names = cfg.outputs[model]
        if cfg.excitation.kind == "sine":
            panels = {}
            for r, res in mine:
                last = signals.last_periods(res.time, {disp: res[disp], force: res[force]}, r.frequency)
                key = f"{r.frequency:g} Hz, level {r.level:g}"
                panels.setdefault(key, []).append((r.set_name, last[disp], last[force]))
            plots.loops(out_dir / f"{model}_loops.png", list(panels.items()), disp, force, units,
                        f"{title}: {model}, steady-state loops")
            continue
        curves = [(f"{r.set_name}, level {r.level:g}", res.time, {n: res[n] for n in names}) for r, res in mine]
        plots.time_histories(out_dir / f"{model}_time.png", curves, names, units, f"{title}: {model}")
        fs = 1 / cfg.output_interval
        main = names[0]
        plots.psd_overlay(out_dir / f"{model}_psd.png", [(c[0], c[2][main], fs) for c in curves], main, units,
                          f"{title}: {model}", segment_s=min(8.0, cfg.stop_time / 4))
        r0, res0 = mine[0]
        plots.spectrogram(out_dir / f"{model}_spectrogram.png", res0[main], fs, main, units,
                          f"{title}: {model}, {r0.set_name}, level {r0.level:g}",
                          f_max=1.5 * cfg.excitation.f_end)
        exc = excitation_of(cfg, r0.level, None)
        plots.instantaneous_frequency(out_dir / f"{model}_instantaneous_frequency.png", res0.time, [
            ("excitation (prescribed)", exc.frequency(res0.time)),
            (f"{main} (Hilbert)", signals.instantaneous_frequency(res0[main], fs))], f"{title}: {model}")
        if cfg.excitation.loops_at:
            panels = []
            for f_cut in cfg.excitation.loops_at:
                curves_cut = []
                for r, res in mine:
                    e = excitation_of(cfg, r.level, None)
                    sel = _one_period_at(e, res.time, f_cut)
                    if sel is not None:
                        curves_cut.append((f"{r.set_name}, level {r.level:g}", res[disp][sel], res[force][sel]))
                panels.append((f"{f_cut:g} Hz (cut from the sweep)", curves_cut))
            plots.loops(out_dir / f"{model}_sweep_loops.png", panels, disp, force, units,
                        f"{title}: {model}, loops cut out of the sweep")


def _one_period_at(exc: Excitation, t: np.ndarray, f_cut: float):
    """Sample slice of one excitation period centred where the sweep passes f_cut (None if it does not)."""
    f = exc.frequency(t)
    idx = np.nonzero(f >= f_cut)[0]
    if len(idx) == 0 or f_cut <= 0:
        return None
    i = idx[0]
    n = int(round(1 / f_cut / (t[1] - t[0])))
    lo, hi = max(0, i - n // 2), min(len(t), i - n // 2 + n)
    return slice(lo, hi)
