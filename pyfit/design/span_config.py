"""The span a design check is for (`stockbridge design-check SPAN.toml`). SI units; a TOML file:

    [conductor]
    type = "drake"                 # from pyfit.design.conductor.CONDUCTORS, or every field below:
    # name, diameter [m], mass_per_length [kg/m], rts [N], ei_min, ei_max [N·m²],
    # outer_wire_diameter [m], outer_youngs_modulus [Pa], aluminium_layers
    [span]
    length = 300.0                 # m
    tension_rts = 0.20             # tension as a fraction of RTS (or: tension = N)
    [self_damping]
    law = "noiseux1991"            # a law of pyfit.design.conductor.SELF_DAMPING_LAWS, or "viscous"
    k = 1.87                       # the law's constant (optional: estimated from the conductor)
    zeta = 2e-4                    # viscous only
    [wind]                         # all optional
    curve = "cigre"                # wind power: a curve of pyfit.design.wind.CURVES (CIGRE or a published one)
    turbulence = 0.0               # turbulence intensity I_v [-]
    weibull_shape = 2.0
    weibull_scale = 4.0            # m/s
    speed_range = [1.0, 7.0]       # m/s, the aeolian range
    strouhal = [0.185, 0.2]
    aeolian_fraction = 1.0         # fraction of that time the wind excites aeolian vibration
    [damper]                       # the damper FMU (DamperElement), optional
    nominal = "my_damper.toml"     # a nominal-model file (relative to this file) ...
    parameters = { k_bw1 = 900.0 } # ... and/or FMU parameters, e.g. a fit's result (these win)
    impedance_file = "test.csv"    # or the damper's measured impedance (pyfit/io/impedance.py) instead of the FMU
    amplitudes = [1e-5, 3e-2]      # m, clamp amplitudes of the damper power table (log-spaced)
    n_amplitudes = 10
    n_frequencies = 20             # log-spaced over the aeolian band
    [placement]                    # optional
    max_dampers = 2
    x_range = [0.5, 3.0]           # m from the suspension clamp
    step = 0.25                    # m, grid before the local refinement
    min_spacing = 0.5              # m between dampers
"""
from __future__ import annotations

import pathlib
from dataclasses import dataclass, field

from pyfit.design.conductor import CONDUCTORS, SELF_DAMPING_LAWS, ConductorType, PowerLaw, self_damping_constant
from pyfit.design.fatigue import WindClimate
from pyfit.design.wind import CURVES, WindPower
from pyfit.io.nominal import load_nominal
from pyfit.io.schema import check_bounds, check_numbers, check_sections, check_table, fail, read_toml

CONDUCTOR_FIELDS = {"name": (str, True, None), "diameter": ("number", True, None),
                    "mass_per_length": ("number", True, None), "rts": ("number", True, None),
                    "ei_min": ("number", True, None), "ei_max": ("number", True, None),
                    "outer_wire_diameter": ("number", True, None), "outer_youngs_modulus": ("number", True, None),
                    "aluminium_layers": (int, True, None)}


@dataclass(frozen=True)
class SpanDesign:
    """Everything a design check needs (SI units)."""

    path: pathlib.Path
    conductor: ConductorType
    length: float
    tension: float
    self_damping: tuple[PowerLaw, float] | None  # None: viscous with zeta
    zeta: float
    wind: WindPower
    climate: WindClimate
    damper_parameters: dict[str, float] = field(default_factory=dict)
    impedance_file: pathlib.Path | None = None  # a measured impedance test used instead of the damper FMU
    amplitudes: tuple[float, float] = (1e-5, 3e-2)
    n_amplitudes: int = 10
    n_frequencies: int = 20
    max_dampers: int = 2
    x_range: tuple[float, float] = (0.5, 3.0)
    step: float = 0.25
    min_spacing: float = 0.5


def _positive(path, key, value):
    if not value > 0:
        fail(path, key, f"must be > 0, not {value!r}")
    return value


def _conductor(doc: dict, path) -> ConductorType:
    table = doc.get("conductor", {})
    if "type" in table:
        if set(table) != {"type"}:
            fail(path, "conductor", "give either type or the conductor's fields, not both",
                 f"type = one of {', '.join(CONDUCTORS)}")
        if table["type"] not in CONDUCTORS:
            fail(path, "conductor.type", f"unknown conductor {table['type']!r}", ", ".join(CONDUCTORS))
        return CONDUCTORS[table["type"]]
    c = check_table(table, path, "conductor", CONDUCTOR_FIELDS)
    for key in CONDUCTOR_FIELDS:
        if key != "name":
            _positive(path, f"conductor.{key}", c[key])
    if c["ei_min"] > c["ei_max"]:
        fail(path, "conductor.ei_min", "larger than ei_max", "ei_min ≤ ei_max")
    return ConductorType(**c)


def _tension(doc, path, conductor) -> tuple[float, float]:
    """[span]: its length [m] and the tension [N] (given, or as a share of the conductor's RTS)."""
    span = check_table(doc["span"], path, "span", {"length": ("number", True, None),
                                                   "tension_rts": ("number", False, None),
                                                   "tension": ("number", False, None)})
    if (span["tension"] is None) == (span["tension_rts"] is None):
        fail(path, "span", "give exactly one of tension [N] and tension_rts [-]")
    tension = span["tension"] if span["tension"] is not None else span["tension_rts"] * conductor.rts
    _positive(path, "span.tension", tension)
    _positive(path, "span.length", span["length"])
    return span["length"], tension


def _self_damping(doc, path, conductor) -> tuple:
    """[self_damping]: a power law and its constant (None for the viscous law), and the viscous damping ratio."""
    sd = check_table(doc.get("self_damping", {}), path, "self_damping",
                     {"law": (str, False, "noiseux1991"), "k": ("number", False, None), "zeta": ("number", False, None)})
    if sd["law"] == "viscous":
        if sd["zeta"] is None:
            fail(path, "self_damping.zeta", "missing (the viscous law needs the modal damping ratio)")
        return None, sd["zeta"]
    if sd["law"] not in SELF_DAMPING_LAWS:
        fail(path, "self_damping.law", f"unknown law {sd['law']!r}", ", ".join([*SELF_DAMPING_LAWS, "viscous"]))
    law = SELF_DAMPING_LAWS[sd["law"]], sd["k"] if sd["k"] is not None else self_damping_constant(conductor)
    return law, sd["zeta"] or 0.0


def _wind(doc, path) -> tuple[WindPower, WindClimate]:
    """[wind]: the wind power curve and turbulence, and the climate (Weibull speeds, aeolian range, Strouhal)."""
    defaults = WindClimate()
    w = check_table(doc.get("wind", {}), path, "wind", {
        "curve": (str, False, "cigre"), "turbulence": ("number", False, 0.0),
        "weibull_shape": ("number", False, defaults.weibull_shape),
        "weibull_scale": ("number", False, defaults.weibull_scale), "speed_range": ("floats", False, None),
        "strouhal": ("floats", False, None), "aeolian_fraction": ("number", False, defaults.aeolian_fraction)})
    if w["curve"] not in CURVES:
        fail(path, "wind.curve", f"unknown wind power curve {w['curve']!r}", ", ".join(CURVES))
    if w["turbulence"] < 0:
        fail(path, "wind.turbulence", f"{w['turbulence']} is negative", "a turbulence intensity ≥ 0")
    speed_range = check_bounds(w["speed_range"], path, "wind.speed_range") if w["speed_range"] else defaults.speed_range
    strouhal = check_bounds(w["strouhal"], path, "wind.strouhal") if w["strouhal"] else defaults.strouhal
    if not 0 < w["aeolian_fraction"] <= 1:
        fail(path, "wind.aeolian_fraction", f"{w['aeolian_fraction']} is not a fraction", "0 < value ≤ 1")
    return WindPower(w["curve"], w["turbulence"]), WindClimate(
        _positive(path, "wind.weibull_shape", w["weibull_shape"]),
        _positive(path, "wind.weibull_scale", w["weibull_scale"]), speed_range, strouhal, w["aeolian_fraction"])


def _placement(doc, path) -> dict:
    pl = check_table(doc.get("placement", {}), path, "placement", {
        "max_dampers": (int, False, 2), "x_range": ("floats", False, None), "step": ("number", False, 0.25),
        "min_spacing": ("number", False, 0.5)})
    if not 1 <= pl["max_dampers"] <= 4:
        fail(path, "placement.max_dampers", f"{pl['max_dampers']}", "1 to 4")
    pl["x_range"] = check_bounds(pl["x_range"], path, "placement.x_range") if pl["x_range"] else (0.5, 3.0)
    return pl


def _damper(doc, path) -> dict:
    """[damper]: the FMU's parameters (a nominal file and overrides) or a measured impedance, and the table's
    amplitudes and grid."""
    d = check_table(doc.get("damper", {}), path, "damper", {
        "nominal": (str, False, None), "parameters": (dict, False, {}), "impedance_file": (str, False, None),
        "amplitudes": ("floats", False, None),
        "n_amplitudes": (int, False, 10), "n_frequencies": (int, False, 20)})
    params = load_nominal(path.parent / d["nominal"]).parameters() if d["nominal"] else {}
    params.update(check_numbers(d["parameters"], path, "damper.parameters"))
    d["parameters"] = params
    d["amplitudes"] = check_bounds(d["amplitudes"], path, "damper.amplitudes") if d["amplitudes"] else (1e-5, 3e-2)
    return d


def _check_damper(d: dict, path) -> pathlib.Path | None:
    """The damper table's grid sizes, and its measured impedance file (which replaces the FMU) if any."""
    for key in ("n_amplitudes", "n_frequencies"):
        if d[key] < 2:
            fail(path, f"damper.{key}", f"{d[key]}", "at least 2")
    impedance_file = path.parent / d["impedance_file"] if d["impedance_file"] else None
    if impedance_file is not None and (d["parameters"] or d["nominal"]):
        fail(path, "damper.impedance_file", "a measured impedance replaces the damper FMU: give no nominal or "
             "parameters with it")
    return impedance_file


def load_span_design(path) -> SpanDesign:
    """Read and check a SPAN.toml; errors name the file and key (pyfit.io.schema format)."""
    path = pathlib.Path(path)
    doc = read_toml(path)
    check_sections(doc, path, ("conductor", "span", "self_damping", "wind", "damper", "placement"),
                   required=("conductor", "span"))
    conductor = _conductor(doc, path)
    length, tension = _tension(doc, path, conductor)
    self_damping, zeta = _self_damping(doc, path, conductor)
    power, climate = _wind(doc, path)
    d = _damper(doc, path)
    pl = _placement(doc, path)
    impedance_file = _check_damper(d, path)
    return SpanDesign(path, conductor, length, tension, self_damping, zeta, power, climate, d["parameters"],
                      impedance_file, d["amplitudes"], d["n_amplitudes"], d["n_frequencies"], pl["max_dampers"],
                      pl["x_range"], _positive(path, "placement.step", pl["step"]),
                      _positive(path, "placement.min_spacing", pl["min_spacing"]))
