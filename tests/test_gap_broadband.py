"""A diagnosis on data this project did not write, of the kind a real oscillator gives: one long record of a
Duffing oscillator (cubic hardening spring) under broadband noise at three rising levels, integrated by
scipy (DOP853, not the FMU), cut into three segments (the second and third do not start at rest), with
sensor noise on force and displacement, written the way a DAQ exports: comment lines, the displacement in
mm, an extra temperature column, a time column rounded to 6 significant digits, the input band up to
0.65 x Nyquist (no quiet band above it)."""
import json

import numpy as np
import pytest
import scipy.signal as ss
from scipy.integrate import solve_ivp

from pyfit.gap import diagnose as dg

FS = 610.35  # Hz, a DAQ's rate
SEGMENT_S = 20.0
M, C, K, K3 = 2.0, 60.0, 1e5, 1e10  # kg, N·s/m, N/m, N/m³
LEVELS = (8.0, 20.0, 40.0)  # input RMS per segment [N]
NOISE_Y, NOISE_U = 2e-6, 0.02  # sensor noise: m, N


@pytest.fixture(scope="module")
def duffing_dataset(tmp_path_factory):
    rng = np.random.default_rng(7)
    n = int(SEGMENT_S * FS)
    b, a = ss.butter(6, 200 / (FS / 2))
    u = np.concatenate([lv * ss.lfilter(b, a, rng.standard_normal(n)) for lv in LEVELS])
    for j in range(3):
        u[j * n:(j + 1) * n] *= LEVELS[j] / np.std(u[j * n:(j + 1) * n])
    t = np.arange(len(u)) / FS

    def rhs(tt, s):
        i = min(int(tt * FS), len(u) - 2)
        f = u[i] + (tt * FS - i) * (u[i + 1] - u[i])
        return [s[1], (f - C * s[1] - K * s[0] - K3 * s[0] ** 3) / M]

    y = solve_ivp(rhs, (0, t[-1]), [0.0, 0.0], t_eval=t, method="DOP853", rtol=1e-10, atol=1e-14,
                  max_step=0.5 / FS).y[0]
    y_meas = y + NOISE_Y * rng.standard_normal(len(y))
    u_meas = u + NOISE_U * rng.standard_normal(len(u))
    out = tmp_path_factory.mktemp("duffing")
    for j in range(3):
        s = slice(j * n, (j + 1) * n)
        lines = ["# exported by the bench DAQ", "# channels: time, force, displacement, temperature",
                 "Time [s],Force [N],Disp [mm],Temp [C]"]
        lines += [f"{ti:.6g},{ui:.5g},{yi * 1e3:.5g},21.3" for ti, ui, yi in zip(t[s] - t[s][0], u_meas[s], y_meas[s])]
        (out / f"seg{j + 1}.csv").write_text("\n".join(lines) + "\n")
        (out / f"seg{j + 1}.toml").write_text(
            f'model = "SDOFBoucWen"\nsample_rate_hz = {FS}\ntime_column = "Time [s]"\nlevel = "segment {j + 1}"\n'
            '[inputs]\n"Force [N]" = { unit = "N", model_variable = "u" }\n'
            '[outputs]\n"Disp [mm]" = { unit = "mm", model_variable = "y" }\n')
    return out


def test_broadband_segments_of_a_duffing_oscillator_are_diagnosed_as_cubic_stiffness(duffing_dataset, fmu_dir,
                                                                                      tmp_path, measured):
    rep = dg.diagnose("sdof", duffing_dataset, tmp_path / "out", fmu_dir=fmu_dir, workers=2, progress=False)
    assert rep["verdict"] == "gap explained by cubic_stiffness"
    assert rep["gap"]["noise_floor_method"] == ["local polynomial, lowest level"]
    assert rep["level_order"] == "input RMS"  # the sidecars give labels only: the segments order by their RMS
    assert "Levels ordered by input RMS." in (tmp_path / "out" / "report.md").read_text()
    best = rep["ranking"][0]
    measured("Duffing broadband segments (independent solver, DAQ-style files): held-out shrink [%]",
             best["shrink_pct"], 80.0, at_least=True)
    measured("Duffing broadband segments: |fitted k3 / true k3 - 1|", abs(best["params"]["k3"] / K3 - 1), 0.05)
    # the floor: the sensor noise of the held-out segment, plus the measured force's noise through the model
    held = next(f for f in rep["gap"]["by_level"] if f["held_out"])
    y = np.genfromtxt(duffing_dataset / f"{held['file']}.csv", delimiter=",", skip_header=3)[:, 2] * 1e-3
    true_sensor_floor = NOISE_Y / np.sqrt(np.mean(y**2))
    measured("Duffing broadband segments: noise floor / sensor noise alone (>= 1: the force noise adds)",
             rep["gap"]["noise_floor"] / true_sensor_floor, 1.5)
    assert rep["gap"]["noise_floor"] >= true_sensor_floor
    assert json.loads((tmp_path / "out" / "report.json").read_text())["verdict"] == rep["verdict"]
