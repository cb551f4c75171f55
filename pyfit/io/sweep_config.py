"""TOML study files -> validated dataclasses. Every error names the file, the key and what is allowed."""
from __future__ import annotations

import pathlib
from dataclasses import dataclass, field

from pyfit.catalog import EXAMPLES
from pyfit.io.schema import ConfigError, check_numbers, check_sections, check_table, fail, read_toml

__all__ = ["ConfigError", "SweepConfig", "load_sweep"]

EXCITATION_KINDS = {"sine": 1, "linear_sweep": 2, "log_sweep": 3, "cv_linear_sweep": 4, "cv_log_sweep": 5}


@dataclass
class ExcitationConfig:
    """Built-in excitation of every run; levels are amplitudes (N, m, or m/s for the cv_ kinds)."""

    kind: str
    levels: list[float]
    frequencies: list[float] = field(default_factory=list)  # sine: one run per frequency [Hz]
    f_start: float = 0.0
    f_end: float = 60.0
    rate: float = 0.5  # Hz/s
    octaves_per_minute: float = 1.0
    t_ramp: float = 0.0
    loops_at: list[float] = field(default_factory=list)  # sweeps: frequencies [Hz] at which to cut loops

    @property
    def exc_type(self) -> int:
        return EXCITATION_KINDS[self.kind]


@dataclass
class ParameterSet:
    name: str
    values: dict[str, float]


@dataclass
class SweepConfig:
    """A sweep study: models x parameter sets x excitation levels (x sine frequencies)."""

    path: pathlib.Path
    models: list[str]
    stop_time: float
    output_interval: float
    outputs: dict[str, list[str]]  # model -> output names
    excitation: ExcitationConfig
    parameters: dict[str, float]
    parameter_sets: list[ParameterSet]
    tolerance: float = 1e-8
    title: str = ""


def _study(doc, path) -> dict:
    st = check_table(doc["study"], path, "study", {
        "models": ("strings", True, None), "stop_time": (float, True, None), "output_interval": (float, False, 1e-3),
        "outputs": ("strings", False, None), "tolerance": (float, False, 1e-8), "title": (str, False, "")})
    for m in st["models"]:
        if m not in EXAMPLES:
            fail(path, "study.models", f"unknown model '{m}'", ", ".join(EXAMPLES))
    if st["stop_time"] <= 0 or st["output_interval"] <= 0 or st["output_interval"] > st["stop_time"]:
        fail(path, "study.stop_time", "stop_time and output_interval must be > 0 with output_interval <= stop_time")
    if abs(round(st["stop_time"] / st["output_interval"]) * st["output_interval"] - st["stop_time"]) > 1e-9:
        fail(path, "study.output_interval", "stop_time must be a whole number of output intervals")
    return st


def _excitation(doc, path) -> ExcitationConfig:
    ex = check_table(doc["excitation"], path, "excitation", {
        "kind": (str, True, None), "levels": ("floats", True, None), "frequencies": ("floats", False, []),
        "f_start": (float, False, 0.0), "f_end": (float, False, 60.0), "rate": (float, False, 0.5),
        "octaves_per_minute": (float, False, 1.0), "t_ramp": (float, False, 0.0), "loops_at": ("floats", False, [])})
    if ex["kind"] not in EXCITATION_KINDS:
        fail(path, "excitation.kind", f"unknown kind '{ex['kind']}'", ", ".join(EXCITATION_KINDS))
    if not ex["levels"]:
        fail(path, "excitation.levels", "needs at least one level")
    if ex["kind"] == "sine" and not ex["frequencies"]:
        fail(path, "excitation.frequencies", "a sine study needs at least one frequency [Hz]")
    if ex["kind"] != "sine" and (ex["f_end"] <= ex["f_start"] or ex["rate"] <= 0):
        fail(path, "excitation.f_end", "a sweep needs f_end > f_start and rate > 0")
    if ex["kind"] in ("log_sweep", "cv_linear_sweep", "cv_log_sweep") and ex["f_start"] <= 0:
        fail(path, "excitation.f_start", "log and constant-velocity sweeps need f_start > 0")
    return ExcitationConfig(**ex)


def _parameter_sets(doc, path) -> list[ParameterSet]:
    sets = []
    for i, s in enumerate(doc.get("parameter_sets", [{"name": "default"}])):
        if "name" not in s or not isinstance(s["name"], str):
            fail(path, f"parameter_sets[{i}].name", "missing (a string)")
        sets.append(ParameterSet(s["name"], check_numbers({k: v for k, v in s.items() if k != "name"}, path,
                                                         f"parameter_sets[{i}]")))
    if len({s.name for s in sets}) != len(sets):
        fail(path, "parameter_sets", "names must be unique")
    return sets


def _outputs(st: dict, path, parameters: dict, sets: list, fmu_variables) -> dict:
    """Each model's outputs (the study's, else every output of the FMU), its names checked against the FMU."""
    outputs = {}
    for m in st["models"]:
        outputs[m] = st["outputs"] or []
        if fmu_variables is None:
            continue
        iface = fmu_variables(m)
        for name in list(parameters) + [k for s in sets for k in s.values]:
            if name not in iface.parameters:
                fail(path, "parameters", f"model {m} has no parameter '{name}'", ", ".join(sorted(iface.parameters)))
        for o in outputs[m]:
            if o not in iface.variables:
                fail(path, "study.outputs", f"model {m} has no variable '{o}'", ", ".join(iface.outputs))
        outputs[m] = outputs[m] or list(iface.outputs)
    return outputs


def load_sweep(path: str | pathlib.Path, fmu_variables=None, nominal=None) -> SweepConfig:
    """Read and validate a sweep study file.

    nominal: a described system (pyfit.io.nominal.NominalModel): its parameters apply to every run, under
    the study's own [parameters] and parameter sets.

    fmu_variables(model) -> an object with .parameters (names that can be set), .variables (all names)
    and .outputs (the FMU's outputs, the default); used to reject unknown names.
    """
    path = pathlib.Path(path)
    doc = read_toml(path, ConfigError)
    check_sections(doc, path, ("study", "excitation", "parameters", "parameter_sets"), ("study", "excitation"))
    st = _study(doc, path)
    excitation = _excitation(doc, path)
    parameters = {**(nominal.parameters() if nominal else {}),
                  **check_numbers(doc.get("parameters", {}), path, "parameters")}
    sets = _parameter_sets(doc, path)
    outputs = _outputs(st, path, parameters, sets, fmu_variables)
    return SweepConfig(path, st["models"], st["stop_time"], st["output_interval"], outputs, excitation, parameters,
                       sets, st["tolerance"], st["title"])
