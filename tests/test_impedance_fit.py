"""The damper FMU fitted to an IEC 61897 characteristic test made by the independent CasADi reference damper:
clamp impedance at two clamp-velocity levels with measurement noise, through `python scripts/fit.py`."""
import json
import subprocess
import sys
import pathlib

import numpy as np
import pytest

from pyfit.io.impedance import read_impedance, write_impedance
from pyfit.reference.impedance import reference_impedance

ROOT = pathlib.Path(__file__).resolve().parents[1]
TRUTH = {"k_bw1": 400.0, "k_bw2": 350.0}  # N/m; the FMU's defaults are 300 and 500
LEVELS = [0.02, 0.05]  # m/s, clamp velocity amplitudes (theory §1.3 test levels ≤ 0.05 m/s)
NOISE = (0.005, np.radians(0.3))  # 0.5 % in |Z|, 0.3° in phase
# (frequencies [Hz], free parameters): the default run fits k_bw1 at two frequencies; the slow one both
# stiffnesses at four, through both damper resonances
CASES = {"short": ([10.0, 30.0], ["k_bw1"]),
         "full": ([10.0, 17.0, 30.0, 45.0], ["k_bw1", "k_bw2"])}


@pytest.mark.parametrize("case", [pytest.param("short"), pytest.param("full", marks=pytest.mark.slow)])
def test_damper_fmu_fitted_to_reference_impedance_curves(case, fmu_dir, tmp_path, measured):
    frequencies, free = CASES[case]
    amps, z = reference_impedance(frequencies, LEVELS, TRUTH, noise=NOISE, seed=3)
    csv = write_impedance(tmp_path / "damper_test.csv", frequencies, amps, z, "CasADi reference damper, noisy")
    assert read_impedance(csv).impedance.shape == (len(frequencies), 2)
    fixed = "".join(f"{k} = {v}\n" for k, v in TRUTH.items() if k not in free)
    (tmp_path / "fit.toml").write_text(
        '[fit]\nmodel = "DamperElement"\nmethod = "polish"\nbudget = 30\n[target]\nfile = "damper_test.csv"\n'
        '[objective]\nkind = "impedance"\n[variables]\n' + "".join(f"{k} = [100.0, 1000.0]\n" for k in free)
        + ("[experiment]\n" + fixed if fixed else "")
        + "[report]\ntruth = { " + ", ".join(f"{k} = {TRUTH[k]}" for k in free) + " }\n")
    run = subprocess.run([sys.executable, str(ROOT / "scripts" / "fit.py"), str(tmp_path / "fit.toml"), "--out",
                          str(tmp_path / "out"), "--workers", "1", "--fmus", str(fmu_dir)],
                         capture_output=True, text=True, timeout=900)
    assert run.returncode == 0, run.stderr[-3000:]
    result = json.loads(next((tmp_path / "out").rglob("result.json")).read_text())
    err = result["impedance_error"]
    where = f"{len(LEVELS)} levels × {len(frequencies)} frequencies, free {', '.join(free)}"
    measured(f"damper FMU fitted to noisy reference impedance ({where}): largest |Z| error [%]",
             err["magnitude_percent_max"], 2.0)
    measured(f"damper FMU fitted to noisy reference impedance ({where}): largest phase error [deg]",
             err["phase_deg_max"], 2.0)
    ident = result["identifiability"]
    for name, value, std in zip(ident["names"], ident["values"], ident["std"]):
        measured(f"impedance fit ({where}): |{name} − truth| in reported standard deviations",
                 abs(value - TRUTH[name]) / std, 3.0)
    assert (next((tmp_path / "out").rglob("impedance_abs.png"))).is_file()
