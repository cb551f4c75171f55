"""Withheld-effect datasets: design-section-5 measurements from a truth model that contains one effect
the nominal model lacks (or none: null cases), at three excitation levels.

No inverse crime: the truth is the CasADi reference integrated by CVODES (rtol 1e-10) at 10x the sensor
rate, with the excitation as a continuous sum of sines, seen through a sensor chain (zero-phase FIR
anti-alias filter and decimation) with noise; the diagnosis fits the FMU (another implementation, another
integrator) at the sensor rate. The excitation is a random-odd multisine (odd lines only, one in four
left out as detection lines): a force on the SDOF mass, or the clamp motion of the damper (displacement,
velocity and acceleration recorded, as a shaker controller does). The leading (transient) periods and one
trailing period (filter edge) are dropped, so each file holds steady-state periods.
"""
from __future__ import annotations

import json
import pathlib
from dataclasses import dataclass

import numpy as np

from pyfit.io.data import write_measurement
from pyfit.analysis.excitation import PeriodicSignal, multisine
from pyfit.reference.synthetic import SyntheticSpec, simulate_truth


@dataclass(frozen=True)
class Family:
    """How the test cases of one system are made (SI units)."""

    model: str  # reference model / FMU name
    linear: dict  # truth without any effect (the nominal model's structure)
    withheld: dict  # effect -> truth parameters added to `linear`
    tangent: dict  # parameters that switch every effect off (Bouc-Wen kept as its tangent stiffness)
    levels: tuple  # RMS of the excitation (N or m)
    level_unit: str
    band_hz: tuple
    fs: float
    samples_per_period: int
    lead_periods: int  # transient periods simulated and dropped
    outputs: tuple
    noise: float  # sensor noise standard deviation [m]


SDOF = Family(
    "SDOFBoucWen", {"m": 2.0, "c": 10.0, "k": 1e5, "alpha": 0.0},  # f0 = 35.6 Hz, zeta = 1.1 %
    {"hysteresis": {"k": 5e4, "alpha": 5e4, "beta": 100.0, "gamma": 0.8, "delta": -1.1},
     "cubic_stiffness": {"k3": 3e8}, "coulomb_friction": {"F_c": 1.0, "v_s": 1e-3},
     "quadratic_damping": {"c2": 10.0}, "none": {}},
    {"beta": 0.0, "k3": 0.0, "F_c": 0.0, "c2": 0.0},
    (10.0, 25.0, 50.0), "N", (5.0, 80.0), 500.0, 2048, 1, ("y",), 5e-6)

_DAMPER_OFF = {"k_bw1": 0.0, "k_bw2": 0.0, "k_cs1": 0.0, "k_cs2": 0.0, "F_c1": 0.0, "F_c2": 0.0, "c2_1": 0.0,
               "c2_2": 0.0, "a1": 0.0, "a2": 0.0}
DAMPER = Family(
    "StockbridgeDamper", dict(_DAMPER_OFF),  # the linear FE damper of design 1.3, masses centred on the cable
    {"hysteresis": {"k_bw1": 600.0, "k_bw2": 1000.0, "D": 2e-4},
     "cubic_stiffness": {"k_cs1": 8e8, "k_cs2": 2.4e9},  # hardening: the seed's softening diverges here
     "coulomb_friction": {"F_c1": 0.08, "F_c2": 0.12, "v_s": 1e-3},
     "quadratic_damping": {"c2_1": 12.0, "c2_2": 20.0},
     "mass_eccentricity": {"a1": 0.015, "a2": 0.015},
     "none": {}},
    {"k_bw1": 0.0, "k_bw2": 0.0, "k_cs1": 0.0, "k_cs2": 0.0, "F_c1": 0.0, "F_c2": 0.0, "c2_1": 0.0, "c2_2": 0.0,
     "a1": 0.0, "a2": 0.0},
    (0.05e-3, 0.1e-3, 0.2e-3), "mm", (5.0, 40.0), 500.0, 2048, 2, ("x1", "x2"), 2e-6)

FAMILIES = {"sdof": SDOF, "damper": DAMPER}
PERIODS = 3


def write_dataset(out_dir, family: Family, effect: str, seed: int = 0, periods: int = PERIODS) -> pathlib.Path:
    """Write one dataset (a file per level) whose truth has `effect` ('none' for a null case);
    truth.json beside it records the truth and what the effect changes at each level against the truth
    without it (Bouc-Wen as its tangent stiffness): the output RMS (RMS(y)/RMS(y_tangent) - 1) and the
    output itself (RMS(y - y_tangent)/RMS(y_tangent)); the diagnosis never reads it."""
    if effect not in family.withheld:
        raise ValueError(f"effect '{effect}' unknown for {family.model}; allowed: {', '.join(family.withheld)}")
    out = pathlib.Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    truth = {**family.linear, **family.withheld[effect]}
    spp, fs, lead = family.samples_per_period, family.fs, family.lead_periods
    keep = slice(lead * spp, (lead + periods) * spp)
    rng = np.random.default_rng(seed)
    changes = {}
    for i, level in enumerate(family.levels):
        signal = PeriodicSignal(multisine(spp, fs, *family.band_hz, level, seed, odd=True), fs)
        stop = (lead + periods + 1) * spp / fs
        t, exact, _ = simulate_truth(SyntheticSpec(family.model, signal, stop, fs, list(family.outputs), truth,
                                                   oversample=10))
        clean = simulate_truth(SyntheticSpec(family.model, signal, stop, fs, list(family.outputs),
                                             {**truth, **family.tangent}, oversample=10))[1]
        tk = t[keep] - t[keep][0]
        num = sum(np.mean((exact[o][keep] - clean[o][keep]) ** 2) for o in family.outputs)
        den = sum(np.mean(clean[o][keep] ** 2) for o in family.outputs)
        rms = sum(np.mean(exact[o][keep] ** 2) for o in family.outputs)
        key = f"{level:g}"
        changes[key] = {"rms": float(np.sqrt(rms / den) - 1.0), "output": float(np.sqrt(num / den))}
        if family.model == "SDOFBoucWen":
            inputs = {"u_meas": (signal(t[keep]), "N", "u")}
        else:
            inputs = {"x_base_meas": (signal(t[keep]), "m", "x_base"),
                      "v_base_meas": (signal.derivative(t[keep], 1), "m/s", "v_base"),
                      "a_base_meas": (signal.derivative(t[keep], 2), "m/s2", "a_base")}
        outputs = {f"{o}_meas": (exact[o][keep] + rng.normal(0.0, family.noise, len(tk)), "m", o)
                   for o in family.outputs}
        shown = level * 1e3 if family.level_unit == "mm" else level
        write_measurement(out / f"level{i + 1}_{shown:g}{family.level_unit}.csv", family.model, tk, inputs, outputs,
                          level=f"RMS {shown:g} {family.level_unit}", level_value=shown,
                          excitation={"kind": "multisine", "samples_per_period": spp, "periods": periods,
                                      "f_min": family.band_hz[0], "f_max": family.band_hz[1], "rms": level,
                                      "odd": True},
                          notes=f"synthetic: CasADi reference (cvodes) at 10x the sensor rate, zero-phase FIR "
                                f"anti-alias + decimation, noise {family.noise} m, seed {seed}")
    (out / "truth.json").write_text(json.dumps({"effect": effect, "params": truth, "seed": seed,
                                                "rms_change": changes}, indent=1))
    return out


def write_cases(out_dir, family: str = "sdof", null_seeds=(0, 1, 2), periods: int = PERIODS) -> list[pathlib.Path]:
    """The test cases of a family: each effect withheld (seed 0) and the null case for every noise seed."""
    fam, out = FAMILIES[family], pathlib.Path(out_dir)
    paths = [write_dataset(out / f"{family}_{e}", fam, e, periods=periods) for e in fam.withheld if e != "none"]
    return paths + [write_dataset(out / f"{family}_none_seed{s}", fam, "none", seed=s, periods=periods)
                    for s in null_seeds]
