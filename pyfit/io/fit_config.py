"""Fit study files (TOML) -> validated dataclasses; errors name the file, the key and what is allowed."""
from __future__ import annotations

import pathlib
from dataclasses import dataclass, field

from pyfit.analysis.excitation import Excitation, MultisineInput
from pyfit.catalog import EXAMPLES
from pyfit.io.schema import ConfigError, check_bounds, check_numbers, check_sections, check_table, fail, read_toml

METHODS = ("nno", "nno+polish", "ga", "de", "polish")
# psd_band, psd_log, time: a measured time series (pyfit.io.data); impedance: a damper characteristic test
# (pyfit.io.impedance), DamperElement only
OBJECTIVE_KINDS = ("psd_band", "psd_log", "time", "impedance")


@dataclass
class FreeParameter:
    """A parameter being fitted, with its bounds in SI units."""

    name: str
    lower: float
    upper: float

    def value(self, u: float) -> float:
        return self.lower + float(u) * (self.upper - self.lower)

    def unit(self, value: float) -> float:
        return (value - self.lower) / (self.upper - self.lower)


@dataclass
class ObjectiveChannel:
    """One compared signal: FMU output, measured column, PSD bands [Hz] and weight."""

    output: str
    column: str
    bands: list[tuple[float, float]] = field(default_factory=list)
    weight: float = 1.0


@dataclass
class NNOSettings:
    """The thesis's NNO settings (Tables 4.5, 5.2, 5.7)."""

    init_sim: int = 20
    hidden_sizes: list[int] = field(default_factory=lambda: [15])
    p_size: int = 10
    fun_tol: float = 5e-4
    max_sim: int = 60
    x_tol: float = 1e-3
    y_tol: float = 1e-3
    ga_generations: int = 60
    seed: int = 0
    trust_region: bool = False
    max_epochs: int = 3000  # the surrogate's training: at most this many Adam epochs,
    patience: int = 200  # stopping once the validation loss has not improved for this many


@dataclass
class FitConfig:
    """One fitting study."""

    path: pathlib.Path
    model: str
    method: str
    budget: int
    seed: int
    target_file: pathlib.Path
    synthetic: dict | None  # how to make the target when it is missing
    fixed: dict[str, float]
    objective_kind: str
    channels: list[ObjectiveChannel]
    segment_s: float
    warmup_s: float
    penalty: float
    tolerance: float
    use_inputs: bool
    input_upsample: int  # inputs are upsampled by this factor before they drive the FMU
    input_periodic: bool  # upsample in the frequency domain (whole periods) instead of a cubic spline
    variables: list[FreeParameter]
    nno: NNOSettings
    polish_kinds: list[str]  # polish stages, run in order (e.g. psd_log to get close, then time)
    polish_budgets: list[int]
    ga_pop_size: int
    truth: dict[str, float] = field(default_factory=dict)
    products: list[tuple[str, str]] = field(default_factory=list)
    benchmark: bool = False  # report the RMS error on the official Bouc-Wen validation signals
    nno_log_ratio: bool = False  # the NNO surrogate learns log(P/P_meas) of a psd_band objective

    def problem_key(self) -> str:
        """Identifies the optimisation problem (target, objective, free and fixed parameters), so that
        methods are compared only on the same problem."""
        import hashlib
        import json

        spec = [str(self.target_file.name), self.model, self.objective_kind, self.segment_s, self.warmup_s,
                [(c.output, c.column, c.bands, c.weight) for c in self.channels],
                [(v.name, v.lower, v.upper) for v in self.variables], sorted(self.fixed.items())]
        return hashlib.sha256(json.dumps(spec).encode()).hexdigest()[:16]


def _fit_table(doc, path) -> dict:
    fit = check_table(doc["fit"], path, "fit", {"model": (str, True, None), "method": (str, False, "nno"),
                                                "budget": (int, False, 60), "seed": (int, False, 0),
                                                "tolerance": (float, False, 1e-8)})
    if fit["model"] not in EXAMPLES:
        fail(path, "fit.model", f"unknown model '{fit['model']}'", ", ".join(EXAMPLES))
    if fit["method"] not in METHODS:
        fail(path, "fit.method", f"unknown method '{fit['method']}'", ", ".join(METHODS))
    if fit["budget"] < 2:
        fail(path, "fit.budget", "needs at least 2 true evaluations")
    return fit


def _target_table(doc, path) -> tuple[dict, pathlib.Path, dict | None]:
    """The [target] table, the target file and how to make it when missing ([target.synthetic])."""
    tg = check_table(doc["target"], path, "target", {"file": (str, True, None), "synthetic": (dict, False, None),
                                                     "use_inputs": (bool, False, False),
                                                     "input_upsample": (int, False, 1),
                                                     "input_periodic": (bool, False, False)})
    if tg["input_upsample"] < 1:
        fail(path, "target.input_upsample", f"{tg['input_upsample']} is not a whole factor >= 1")
    target_file = (path.parent / tg["file"]).resolve()
    if tg["synthetic"] is None and not target_file.is_file():
        fail(path, "target.file", f"measurement {target_file} not found (and no [target.synthetic] to make it)")
    return tg, target_file, None if tg["synthetic"] is None else _synthetic_table(tg["synthetic"], path)


def _synthetic_table(raw: dict, path) -> dict:
    """[target.synthetic]: the excitation (a built-in one or a multisine), the sensor rate, outputs and noise."""
    sy = check_table(raw, path, "target.synthetic", {
        "excitation": (dict, False, None), "multisine": (dict, False, None), "stop_time": (float, False, 0.0),
        "sample_rate_hz": (float, True, None), "outputs": ("strings", True, None), "noise_std": (dict, False, {}),
        "parameters": (dict, False, {}), "oversample": (int, False, 10), "seed": (int, False, 1),
        "solver": (str, False, "cvodes"), "anti_alias": (bool, False, True),
        "passband_ripple_db": (float, False, None)})
    if sy["passband_ripple_db"] is not None and not (sy["anti_alias"] and 0 < sy["passband_ripple_db"] < 1):
        fail(path, "target.synthetic.passband_ripple_db", f"{sy['passband_ripple_db']} needs anti_alias = true",
             "a ripple in dB between 0 and 1, e.g. 0.005")
    if (sy["excitation"] is None) == (sy["multisine"] is None):
        fail(path, "target.synthetic", "needs exactly one of excitation and multisine")
    if sy["solver"] not in ("cvodes", "newmark"):
        fail(path, "target.synthetic.solver", f"unknown solver '{sy['solver']}'", "cvodes, newmark")
    try:
        multisine = sy.pop("multisine")
        sy["excitation"] = MultisineInput(**multisine) if multisine is not None else Excitation(**sy["excitation"])
    except (TypeError, ValueError) as exc:
        fail(path, "target.synthetic.excitation", str(exc),
             "excitation: kind, amplitude, f_start, f_end, rate, octaves_per_minute, t_ramp; "
             "multisine: f_min, f_max, rms, samples_per_period, periods, seed")
    if isinstance(sy["excitation"], Excitation) and sy["stop_time"] <= 0:
        fail(path, "target.synthetic.stop_time", "a built-in excitation needs stop_time > 0 [s]")
    sy["noise_std"] = check_numbers(sy["noise_std"], path, "target.synthetic.noise_std")
    sy["parameters"] = check_numbers(sy["parameters"], path, "target.synthetic.parameters")
    return sy


def _objective_table(doc, path, model: str, synthetic) -> tuple[dict, list[ObjectiveChannel]]:
    """[objective]: its kind, settings and compared channels."""
    ob = check_table(doc["objective"], path, "objective", {
        "kind": (str, False, "psd_band"), "channels": (list, False, []), "segment_s": (float, False, 8.0),
        "warmup_s": (float, False, 0.0), "penalty": (float, False, 10.0)})
    if ob["kind"] not in OBJECTIVE_KINDS:
        fail(path, "objective.kind", f"unknown kind '{ob['kind']}'", ", ".join(OBJECTIVE_KINDS))
    if ob["kind"] == "impedance":
        if model != "DamperElement":
            fail(path, "fit.model", f"an impedance objective compares the clamp impedance, which {model} "
                 "does not have", "DamperElement")
        if synthetic is not None:
            fail(path, "target.synthetic", "an impedance target is a measured impedance test file "
                 "(pyfit/io/impedance.py), not a synthetic time series")
    elif not ob["channels"]:
        fail(path, "objective.channels", "missing (the compared signals)")
    return ob, [_channel(ch, path, i, ob["kind"]) for i, ch in enumerate(ob["channels"])]


def _channel(ch, path, i: int, kind: str) -> ObjectiveChannel:
    c = check_table(ch, path, f"objective.channels[{i}]", {"output": (str, True, None), "column": (str, True, None),
                                                            "bands": (list, False, []), "weight": (float, False, 1.0)})
    bands = []
    for b in c["bands"]:
        if not (isinstance(b, list) and len(b) == 2 and all(isinstance(v, (int, float)) for v in b) and b[0] < b[1]):
            fail(path, f"objective.channels[{i}].bands", f"{b!r} is not [low, high] in Hz with low < high")
        bands.append((float(b[0]), float(b[1])))
    if kind != "time" and not bands:
        fail(path, f"objective.channels[{i}].bands", "a psd_band objective needs at least one band")
    return ObjectiveChannel(c["output"], c["column"], bands, c["weight"])


def _variables(doc, path, fixed: dict, model: str, fmu_parameters) -> list[FreeParameter]:
    """[variables] (each with its bounds), every name and fixed one checked against the FMU's parameters."""
    variables = [FreeParameter(name, *check_bounds(b, path, f"variables.{name}"))
                 for name, b in doc["variables"].items()]
    if not variables:
        fail(path, "variables", "no parameter to fit")
    if fmu_parameters is not None:
        known = fmu_parameters(model)
        for name in [v.name for v in variables] + list(fixed):
            if name not in known:
                fail(path, "variables" if name in doc["variables"] else "experiment (or --nominal)",
                     f"model {model} has no parameter '{name}'", ", ".join(sorted(known)))
    return variables


def _nno_table(doc, path, objective_kind: str) -> dict:
    nn = check_table(doc.get("nno", {}), path, "nno", {
        "init_sim": (int, False, 20), "hidden_sizes": (list, False, [15]), "p_size": (int, False, 20),
        "fun_tol": (float, False, 0.0), "x_tol": (float, False, 1e-3), "y_tol": (float, False, 1e-3),
        "ga_generations": (int, False, 50), "trust_region": (bool, False, False),
        "log_ratio": (bool, False, False), "max_epochs": (int, False, NNOSettings.max_epochs),
        "patience": (int, False, NNOSettings.patience)})
    for key in ("max_epochs", "patience"):
        if nn[key] < 1:
            fail(path, f"nno.{key}", f"{nn[key]} training epochs", "a whole number ≥ 1")
    if nn["log_ratio"] and objective_kind != "psd_band":
        fail(path, "nno.log_ratio", "learns log(P/P_meas) of the relative PSD error", 'objective.kind = "psd_band"')
    return nn


def _polish_table(doc, path, objective_kind: str) -> dict:
    """[polish]: the local stages' kinds and budgets (one budget per kind)."""
    raw = dict(doc.get("polish", {}))
    if isinstance(raw.get("budget"), int):
        raw["budget"] = [raw["budget"]]
    pol = check_table(raw, path, "polish", {"kind": ("strings", False, ["time"]), "budget": (list, False, [30])})
    allowed = ("impedance",) if objective_kind == "impedance" else ("psd_band", "psd_log", "time")
    if objective_kind == "impedance" and "kind" not in raw:
        pol["kind"] = ["impedance"]
    for k in pol["kind"]:
        if k not in allowed:
            fail(path, "polish.kind", f"unknown kind '{k}'", f"{', '.join(allowed)} (or a list of them)")
    if len(pol["budget"]) != len(pol["kind"]) or not all(isinstance(b, int) and b > 0 for b in pol["budget"]):
        fail(path, "polish.budget", f"{pol['budget']!r} must be one positive whole number per polish.kind stage")
    return pol


def _nno_settings(nn: dict, fit: dict, pol: dict, path) -> NNOSettings:
    """The NNO settings, its budget what the polish stages of 'nno+polish' leave."""
    nno_budget = fit["budget"] - (sum(pol["budget"]) if fit["method"] == "nno+polish" else 0)
    if nno_budget <= nn["init_sim"] and fit["method"] in ("nno", "nno+polish"):
        fail(path, "nno.init_sim", f"init_sim = {nn['init_sim']} leaves no NNO iteration within the budget "
                                    f"({nno_budget} true evaluations for NNO)")
    return NNOSettings(init_sim=nn["init_sim"], hidden_sizes=[int(h) for h in nn["hidden_sizes"]],
                       p_size=nn["p_size"], fun_tol=nn["fun_tol"], max_sim=nno_budget, x_tol=nn["x_tol"],
                       y_tol=nn["y_tol"], ga_generations=nn["ga_generations"], seed=fit["seed"],
                       trust_region=nn["trust_region"], max_epochs=nn["max_epochs"], patience=nn["patience"])


def load_fit(path: str | pathlib.Path, fmu_parameters=None, nominal=None) -> FitConfig:
    """Read and validate a fit study. fmu_parameters(model) -> set of settable names (to reject unknown ones).
    nominal: a described system (pyfit.io.nominal.NominalModel): its parameters are fixed in every FMU run,
    under the study's [experiment] table and except the fitted variables."""
    path = pathlib.Path(path)
    doc = read_toml(path, ConfigError)
    check_sections(doc, path, ("fit", "target", "experiment", "objective", "variables", "nno", "polish", "ga",
                               "report"), ("fit", "target", "objective", "variables"))
    fit = _fit_table(doc, path)
    tg, target_file, synthetic = _target_table(doc, path)
    fixed = {**{k: v for k, v in (nominal.parameters() if nominal else {}).items() if k not in doc["variables"]},
             **check_numbers(doc.get("experiment", {}), path, "experiment")}
    ob, channels = _objective_table(doc, path, fit["model"], synthetic)
    variables = _variables(doc, path, fixed, fit["model"], fmu_parameters)
    nn = _nno_table(doc, path, ob["kind"])
    pol = _polish_table(doc, path, ob["kind"])
    ga = check_table(doc.get("ga", {}), path, "ga", {"pop_size": (int, False, 20)})
    rep = check_table(doc.get("report", {}), path, "report", {"truth": (dict, False, {}), "products": (list, False, []),
                                                            "benchmark": (bool, False, False)})
    if rep["benchmark"] and fit["model"] != "SDOFBoucWen":
        fail(path, "report.benchmark", "the Bouc-Wen benchmark validation needs model = \"SDOFBoucWen\"")
    return FitConfig(path=path, model=fit["model"], method=fit["method"], budget=fit["budget"], seed=fit["seed"],
                     target_file=target_file, synthetic=synthetic, fixed=fixed, objective_kind=ob["kind"],
                     channels=channels, segment_s=ob["segment_s"], warmup_s=ob["warmup_s"], penalty=ob["penalty"],
                     tolerance=fit["tolerance"], use_inputs=tg["use_inputs"], input_upsample=tg["input_upsample"],
                     input_periodic=tg["input_periodic"], variables=variables, nno=_nno_settings(nn, fit, pol, path),
                     polish_kinds=pol["kind"], polish_budgets=pol["budget"], ga_pop_size=ga["pop_size"],
                     truth=check_numbers(rep["truth"], path, "report.truth"),
                     products=[tuple(p) for p in rep["products"]], benchmark=rep["benchmark"],
                     nno_log_ratio=nn["log_ratio"])
