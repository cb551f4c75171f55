"""Withheld-effect datasets: design-section-5 measurements from a truth model that contains one effect
the nominal model lacks (or none: null cases), at three force levels.

No inverse crime: the truth is the CasADi reference integrated by CVODES (rtol 1e-10) at 10x the sensor
rate, seen through a sensor chain (zero-phase FIR anti-alias filter and decimation) with noise; the
diagnosis fits the FMU (another implementation, another integrator) at the sensor rate. The excitation is
a random-odd multisine force (odd lines 5-80 Hz, one in four left out as detection lines), integrated
with the multisine as a continuous sum of sines for 1 + periods + 1 periods: the first (transient) and last (filter edge) are dropped, so each file holds
steady-state periods, as a laboratory records them.
"""
from __future__ import annotations

import json
import pathlib

import numpy as np

from ..data import write_measurement
from ..excitation import PeriodicSignal, multisine
from ..synthetic import SyntheticSpec, simulate_truth

SDOF_LINEAR = {"m": 2.0, "c": 10.0, "k": 1e5, "alpha": 0.0}  # f0 = 35.6 Hz, zeta = 1.1 %
# effect -> truth parameters added to SDOF_LINEAR (hysteresis: the benchmark's Bouc-Wen, k + alpha = 1e5)
SDOF_WITHHELD = {
    "hysteresis": {"k": 5e4, "alpha": 5e4, "beta": 100.0, "gamma": 0.8, "delta": -1.1},
    "cubic_stiffness": {"k3": 3e8},
    "coulomb_friction": {"F_c": 1.0, "v_s": 1e-3},
    "quadratic_damping": {"c2": 10.0},
    "none": {},
}
LEVELS_N = (10.0, 25.0, 50.0)  # RMS of the force [N]
FS_HZ, SAMPLES_PER_PERIOD, PERIODS = 500.0, 2048, 3
NOISE_M = 5e-6  # sensor noise [m], standard deviation


def _tangent(params: dict) -> dict:
    """The truth with its effect switched off at small amplitude: Bouc-Wen as the stiffness alpha."""
    return {**params, "beta": 0.0, "k3": 0.0, "F_c": 0.0, "c2": 0.0}


def write_sdof_dataset(out_dir, effect: str, seed: int = 0, levels=LEVELS_N, periods: int = PERIODS
                       ) -> pathlib.Path:
    """Write one SDOF dataset (a file per level) whose truth has `effect` ('none' for a null case);
    truth.json beside it records the truth and what the effect changes at each level against the truth
    without it (Bouc-Wen as its tangent stiffness): the output RMS (RMS(y)/RMS(y_tangent) - 1) and the
    output itself (RMS(y - y_tangent)/RMS(y_tangent)); the diagnosis never reads it."""
    if effect not in SDOF_WITHHELD:
        raise ValueError(f"effect '{effect}' unknown; allowed: {', '.join(SDOF_WITHHELD)}")
    out = pathlib.Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    truth = {**SDOF_LINEAR, **SDOF_WITHHELD[effect]}
    spp, keep = SAMPLES_PER_PERIOD, slice(SAMPLES_PER_PERIOD, (periods + 1) * SAMPLES_PER_PERIOD)
    changes = {}
    rng = np.random.default_rng(seed)
    for i, level in enumerate(levels):
        force = PeriodicSignal(multisine(spp, FS_HZ, 5.0, 80.0, level, seed, odd=True), FS_HZ)
        stop = (periods + 2) * spp / FS_HZ
        t, exact, inputs = simulate_truth(SyntheticSpec("SDOFBoucWen", force, stop, FS_HZ, ["y"], truth,
                                                        oversample=10))
        clean = simulate_truth(SyntheticSpec("SDOFBoucWen", force, stop, FS_HZ, ["y"], _tangent(truth),
                                             oversample=10))[1]["y"][keep]
        y = exact["y"][keep]
        changes[f"{level:g}"] = {"rms": float(np.sqrt(np.mean(y**2) / np.mean(clean**2)) - 1.0),
                                 "output": float(np.sqrt(np.mean((y - clean) ** 2) / np.mean(clean**2)))}
        y = y + rng.normal(0.0, NOISE_M, len(y))
        write_measurement(out / f"level{i + 1}_{level:g}N.csv", "SDOFBoucWen", t[keep] - t[keep][0],
                          {"u_meas": (inputs["u"][keep], "N", "u")}, {"y_meas": (y, "m", "y")},
                          level=f"force RMS {level:g} N", level_value=level,
                          excitation={"kind": "multisine", "samples_per_period": spp, "periods": periods,
                                      "f_min": 5.0, "f_max": 80.0, "rms": level, "odd": "true"},
                          notes=f"synthetic: CasADi reference (cvodes) at 10x the sensor rate, zero-phase FIR "
                                f"anti-alias + decimation, noise {NOISE_M} m, seed {seed}")
    (out / "truth.json").write_text(json.dumps({"effect": effect, "params": truth, "seed": seed,
                                                "rms_change": changes}, indent=1))
    return out


def write_sdof_cases(out_dir, null_seeds=(0, 1, 2), periods: int = PERIODS) -> list[pathlib.Path]:
    """The SDOF test cases: each effect withheld (seed 0) and the null case for every noise seed."""
    out = pathlib.Path(out_dir)
    paths = [write_sdof_dataset(out / f"sdof_{e}", e, periods=periods) for e in SDOF_WITHHELD if e != "none"]
    return paths + [write_sdof_dataset(out / f"sdof_none_seed{s}", "none", seed=s, periods=periods)
                    for s in null_seeds]
