"""Sweep studies from TOML files: results with physics checks, and one clear error per bad input."""
import csv
import textwrap

import numpy as np
import pytest

from pyfit.io.sweep_config import ConfigError, load_sweep
from pyfit.runtime.fmu import FmuRunner
from pyfit.runtime.sweep import fmu_interface, run_study

STUDY = """
[study]
models = "SDOFBoucWen"
stop_time = 3.0
output_interval = 1e-4
outputs = ["y", "z"]

[excitation]
kind = "sine"
frequencies = [5.0, 20.0]
levels = [60.0, 120.0]

[[parameter_sets]]
name = "hysteretic"

[[parameter_sets]]
name = "linear"
beta = 0.0
"""


def _write(tmp_path, text, name="study.toml"):
    p = tmp_path / name
    p.write_text(textwrap.dedent(text))
    return p


def test_sweep_study_results_and_linear_energy_per_cycle(fmu_dir, tmp_path, measured):
    cfg = load_sweep(_write(tmp_path, STUDY), lambda m: fmu_interface(fmu_dir / f"{m}.fmu"))
    rows = run_study(cfg, fmu_dir, tmp_path / "out", workers=2, progress=False)
    assert len(rows) == 8 and all(r["ok"] for r in rows)
    with open(tmp_path / "out" / "summary.csv") as f:
        assert len(list(csv.DictReader(f))) == 8
    assert (tmp_path / "out" / "SDOFBoucWen_loops.png").stat().st_size > 10_000
    power_vs_loop = linear_energy = 0.0
    for r in rows:
        power_vs_loop = max(power_vs_loop, abs(r["mean_power_w"] / (r["loop_energy_j"] * r["frequency_hz"]) - 1))
        if r["parameter_set"] == "linear":
            # linear oscillator: energy per cycle = pi * c * omega * Y^2
            y = np.loadtxt(tmp_path / "out" / "runs" / f"{r['label']}.csv", delimiter=",", skiprows=1)[:, 1]
            n = int(round(1 / r["frequency_hz"] / 1e-4))
            amp = (np.max(y[-n:]) - np.min(y[-n:])) / 2
            linear_energy = max(linear_energy, abs(r["loop_energy_j"] / (np.pi * 10.0 * 2 * np.pi * r["frequency_hz"]
                                                                          * amp**2) - 1))
    measured("sweep study, every sine run: |mean power / (loop energy × f) − 1|", power_vs_loop, 1e-4)  # trapezoid loop, O((ωΔt)²)
    measured("sweep study, linear SDOF: |loop energy / (π·c·ω·Y²) − 1|", linear_energy, 0.02)
    hyst = {(r["level"], r["frequency_hz"]): r["loop_energy_j"] for r in rows if r["parameter_set"] == "hysteretic"}
    lin = {(r["level"], r["frequency_hz"]): r["loop_energy_j"] for r in rows if r["parameter_set"] == "linear"}
    assert all(hyst[k] > lin[k] for k in hyst)  # hysteresis dissipates on top of the viscous damper


@pytest.mark.parametrize("change,key", [
    (("kind = \"sine\"", "kind = \"square\""), "excitation.kind"),
    (("levels = [60.0, 120.0]", "levels = []"), "excitation.levels"),
    (("stop_time = 3.0", "stop_time = 3.0\nspeed = 2"), "study.speed"),
    (("beta = 0.0", "betta = 0.0"), "parameters"),
    (("outputs = [\"y\", \"z\"]", "outputs = [\"y\", \"w\"]"), "study.outputs"),
    (("models = \"SDOFBoucWen\"", "models = \"ThreeDOF\""), "study.models"),
    (("frequencies = [5.0, 20.0]", "frequencies = \"fast\""), "excitation.frequencies"),
])
def test_malformed_config_names_file_and_key(fmu_dir, tmp_path, change, key):
    path = _write(tmp_path, STUDY.replace(*change))
    with pytest.raises(ConfigError) as err:
        load_sweep(path, lambda m: fmu_interface(fmu_dir / f"{m}.fmu"))
    assert str(path) in str(err.value) and f"[{key}]" in str(err.value)


def test_missing_config_and_missing_fmu(tmp_path):
    with pytest.raises(ConfigError, match="nope.toml: file not found"):
        load_sweep(tmp_path / "nope.toml")
    with pytest.raises(FileNotFoundError, match="missing.fmu: FMU file not found"):
        FmuRunner(str(tmp_path / "missing.fmu")).simulate(1.0, 0.1, ["y"])


def test_input_with_nan_or_non_uniform_time_is_rejected(runner):
    t = np.linspace(0, 1, 101)
    u = np.sin(t)
    u[40] = np.nan
    with pytest.raises(ValueError, match="input 'u' is not finite at 1 sample.*t = 0.4 s"):
        runner("SDOFBoucWen").simulate(1.0, 0.01, ["y"], {"exc_type": 0}, inputs={"u": u}, input_time=t)
    t2 = t.copy()
    t2[50] += 0.003
    with pytest.raises(ValueError, match="input time column: time column is not uniformly sampled"):
        runner("SDOFBoucWen").simulate(1.0, 0.01, ["y"], {"exc_type": 0}, inputs={"u": np.sin(t)}, input_time=t2)
