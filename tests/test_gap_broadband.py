"""A diagnosis on data this project did not write, of the kind a real oscillator gives: one long record of a
Duffing oscillator (cubic hardening spring) under broadband noise at three rising levels, integrated by
scipy (DOP853, not the FMU), cut into three segments (the second and third do not start at rest), with
sensor noise on force and displacement, written the way a DAQ exports: comment lines, the displacement in
mm, an extra temperature column, a time column rounded to 6 significant digits, the input band up to
0.65 x Nyquist (no quiet band above it). At two scales: the SDOF benchmark's, and an electronic
oscillator's (volts read as m and N: k = 1 N/m, m = 7e-6 kg)."""
from dataclasses import dataclass

import numpy as np
import pytest
import scipy.signal as ss
from scipy.integrate import solve_ivp

from pyfit.gap import diagnose as dg
from pyfit.gap.result import Diagnosis

FS = 610.35  # Hz, a DAQ's rate
SEGMENT_S = 20.0


@dataclass(frozen=True)
class Oscillator:
    """A Duffing oscillator m y'' + c y' + k y + k3 y³ = u and how it was measured (SI units)."""

    m: float  # kg
    c: float  # N·s/m
    k: float  # N/m
    k3: float  # N/m³
    levels: tuple  # input RMS per segment [N]
    noise_y: float  # sensor noise [m]
    noise_u: float  # [N]
    floor_ratio_max: float  # allowed noise floor / sensor noise (the floor also counts the lowest level's distortion)


SCALES = {
    # the SDOF benchmark's scale: 35.6 Hz, displacements of about 0.1 mm; at the lowest level's peaks the
    # resonance moves by 3/8 k3 A²/k = 0.08 %, far inside its half-power width (ζ = 6.7 %): little distortion
    "benchmark": Oscillator(2.0, 60.0, 1e5, 1e10, (8.0, 20.0, 40.0), 2e-6, 0.02, 1.5),
    # an electronic oscillator's scale (volts read as m and N): 60 Hz, ζ = 0.05, k = 1 N/m, m = 7e-6 kg,
    # outputs of about 0.1 "m"; nothing in the diagnosis may be scaled absolutely. At the lowest level's peaks
    # the resonance moves by about 4 %, its half-power width (ζ = 5 %): distortion of some 10 % of that level
    # lands in the local-polynomial floor (measured: 29 × the sensor noise alone)
    "electronic": Oscillator(1.0 / (2 * np.pi * 60) ** 2, 0.1 / (2 * np.pi * 60), 1.0, 7.5, (0.02, 0.05, 0.1),
                             2e-4, 1e-4, 40.0),
}


@pytest.fixture(scope="module", params=[pytest.param("benchmark", marks=pytest.mark.slow),
                                        pytest.param("electronic", marks=pytest.mark.slow)])
def duffing_dataset(request, tmp_path_factory):
    osc = SCALES[request.param]
    rng = np.random.default_rng(7)
    n = int(SEGMENT_S * FS)
    b, a = ss.butter(6, 200 / (FS / 2))
    u = np.concatenate([lv * ss.lfilter(b, a, rng.standard_normal(n)) for lv in osc.levels])
    for j in range(3):
        u[j * n:(j + 1) * n] *= osc.levels[j] / np.std(u[j * n:(j + 1) * n])
    t = np.arange(len(u)) / FS

    def rhs(tt, s):
        i = min(int(tt * FS), len(u) - 2)
        f = u[i] + (tt * FS - i) * (u[i + 1] - u[i])
        return [s[1], (f - osc.c * s[1] - osc.k * s[0] - osc.k3 * s[0] ** 3) / osc.m]

    y = solve_ivp(rhs, (0, t[-1]), [0.0, 0.0], t_eval=t, method="DOP853", rtol=1e-10, atol=1e-14,
                  max_step=0.5 / FS).y[0]
    y_meas = y + osc.noise_y * rng.standard_normal(len(y))
    u_meas = u + osc.noise_u * rng.standard_normal(len(u))
    out = tmp_path_factory.mktemp(f"duffing_{request.param}")
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
    return out, request.param


def test_broadband_segments_of_a_duffing_oscillator_are_diagnosed_as_cubic_stiffness(duffing_dataset, fmu_dir,
                                                                                      tmp_path, measured):
    data, scale = duffing_dataset
    osc = SCALES[scale]
    rep = dg.diagnose("sdof", data, tmp_path / "out", fmu_dir=fmu_dir, workers=2, progress=False)
    assert rep.chosen == ("cubic_stiffness",)
    assert rep.gap.noise_floor_method == ("local polynomial, lowest level",)
    assert rep.level_order == "input RMS"  # the sidecars give labels only: the segments order by their RMS
    assert "Levels ordered by input RMS." in (tmp_path / "out" / "report.md").read_text()
    best = rep.ranking[0]
    measured(f"Duffing broadband segments ({scale} scale; independent solver, DAQ-style files): held-out shrink [%]",
             best.shrink_pct, 80.0, at_least=True)
    measured(f"Duffing broadband segments ({scale} scale): |fitted k3 / true k3 - 1|",
             abs(best.params["k3"] / osc.k3 - 1), 0.05)
    # the floor: the sensor noise of the held-out segment, plus the measured force's noise through the model
    held = next(f for f in rep.gap.by_level if f.held_out)
    y = np.genfromtxt(data / f"{held.file}.csv", delimiter=",", skip_header=3)[:, 2] * 1e-3
    true_sensor_floor = osc.noise_y / np.sqrt(np.mean(y**2))
    measured(f"Duffing broadband segments ({scale} scale): noise floor / sensor noise alone (>= 1: the force "
             "noise and the distortion add)",
             rep.gap.noise_floor / true_sensor_floor, osc.floor_ratio_max)
    assert rep.gap.noise_floor >= true_sensor_floor
    assert Diagnosis.read(tmp_path / "out" / "report.json").to_json() == rep.to_json()
