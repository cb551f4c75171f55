"""Records as a user brings them, prepared for the diagnosis: a segment cut from a long record, a clamp
motion recorded as one quantity only, channels that are not FMU variables."""
import numpy as np
import pytest

from pyfit.analysis.excitation import Excitation
from pyfit.gap import simulate as sim
from pyfit.gap.diagnose import DiagnoseError, diagnose
from pyfit.io.data import read_measurement, write_measurement
from pyfit.reference.synthetic import SyntheticSpec, simulate_truth

TRUTH = {"m": 2.0, "c": 10.0, "k": 1e5, "alpha": 0.0}  # 35.6 Hz, zeta 1.1 %: time constant 0.41 s


def test_segment_cut_from_a_long_record_is_compared_after_its_transient(tmp_path, runner, measured):
    fs = 500.0
    exc = Excitation(2, 50.0, 20.0, 50.0, 1.5)  # force sweep through the resonance, from rest
    t, y, u = simulate_truth(SyntheticSpec("SDOFBoucWen", exc, 20.0, fs, ["y"], TRUTH, oversample=10,
                                           passband_ripple_db=0.005))
    cut = slice(int(4 * fs), len(t))  # starts at 4 s, in full motion (16 s: a quarter is the 4 s window)
    path = write_measurement(tmp_path / "seg.csv", "SDOFBoucWen", t[cut] - t[cut][0], {"F": (u["u"][cut], "N", "u")},
                             {"Y": (y["y"][cut], "m", "y")})
    rec = sim.record_of(read_measurement(path), transient_s=4.0)
    assert rec.first == int(4.0 * fs) and rec.n == len(t[cut]) - rec.first
    out = sim.simulate(runner("SDOFBoucWen"), rec, {**TRUTH, "exc_type": 0})
    err = np.sqrt(np.mean((out["y"] - rec.outputs["y"]) ** 2) / np.mean(rec.outputs["y"] ** 2))
    # the start-up transient decays as exp(-t/0.41 s): 6e-5 of the motion after 4 s; the rest is the spline
    # upsampling of the 500 Hz input and the sensor chain (0.005 dB anti-alias filter: 6e-4)
    measured("segment cut from a long SDOF record (from 4 s, not at rest), simulated from rest with the truth, "
             "first 4 s dropped: NRMSE", err, 2e-3)


def test_clamp_motion_recorded_as_displacement_only_gives_all_three(tmp_path):
    fs, f = 500.0, 12.0
    t = np.arange(int(10 * fs)) / fs
    x = 2e-4 * np.sin(2 * np.pi * f * t) * np.minimum(t / 2, 1) ** 3
    path = write_measurement(tmp_path / "d.csv", "StockbridgeDamper", t, {"X": (x, "mm", "x_base")},
                             {"Y": (x, "m", "x1")})
    rec = sim.record_of(read_measurement(path), ("x_base", "v_base", "a_base"))
    assert set(rec.inputs) == {"x_base", "v_base", "a_base"} and rec.derived == ("v_base", "a_base")
    steady = t > 3
    w = 2 * np.pi * f
    v_ref, a_ref = 2e-4 * w * np.cos(w * t), -2e-4 * w**2 * np.sin(w * t)
    for name, ref in (("v_base", v_ref), ("a_base", a_ref)):  # RMS over the steady part (edges ring briefly)
        err = np.sqrt(np.mean((rec.inputs[name][steady] - ref[steady]) ** 2) / np.mean(ref[steady] ** 2))
        assert err < 5e-3, (name, err)


def test_a_channel_that_is_not_an_fmu_variable_is_refused(tmp_path, fmu_dir):
    fs = 500.0
    t = np.arange(int(4 * fs)) / fs
    ramp = np.minimum(t, 1.0) ** 3  # from rest
    for i, amp in enumerate((1.0, 2.0)):
        write_measurement(tmp_path / f"l{i}.csv", "SDOFBoucWen", t, {"F": (amp * ramp * np.sin(220 * t), "N", "u")},
                          {"Y": (1e-5 * amp * ramp * np.sin(220 * t), "m", "y_mass")}, level_value=amp)
    with pytest.raises(DiagnoseError, match=r"l0.toml: \[outputs\] model_variable 'y_mass' is not a variable of "
                                            r"SDOFBoucWen; allowed: F, a, v, y, z"):
        diagnose("sdof", tmp_path, tmp_path / "out", fmu_dir=fmu_dir, progress=False)
