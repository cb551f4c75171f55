"""Clamp kinematics from one recorded quantity: the other two against the analytic motion."""
import numpy as np
import pytest

from pyfit.analysis import kinematics

FS = 750.0


def sweep_motion(t):
    """x, v, a of a constant-velocity-amplitude linear sweep 5 -> 40 Hz (0.05 m/s), analytic."""
    f0, rate, v0 = 5.0, 1.0, 0.05
    w = 2 * np.pi * (f0 + rate * t)
    phase = 2 * np.pi * (f0 * t + 0.5 * rate * t**2)
    dw = 2 * np.pi * rate
    x = -v0 / w * np.cos(phase)
    v = v0 * np.sin(phase) + v0 * dw / w**2 * np.cos(phase)
    a = v0 * w * np.cos(phase) - 2 * v0 * dw**2 / w**3 * np.cos(phase) - v0 * dw / w * np.sin(phase)
    return {"x": x, "v": v, "a": a}


def band_rms_error(est, ref, band):
    """RMS of (est - ref) relative to RMS(ref), both restricted to the excited band (FFT mask)."""
    f = np.fft.rfftfreq(len(ref), 1 / FS)
    m = (f >= band[0]) & (f <= band[1])
    e, r = np.fft.rfft(est - ref)[m], np.fft.rfft(ref)[m]
    return np.sqrt(np.sum(np.abs(e) ** 2) / np.sum(np.abs(r) ** 2))


@pytest.mark.parametrize("given", ["x", "a"])
def test_derived_kinematics_of_a_sweep_segment_match_the_analytic_motion(given, measured):
    # a segment cut from a long record (12-30 s of the sweep: 17-35 Hz), not at rest, not periodic,
    # with an accelerometer-like offset and drift on top
    t = 12.0 + np.arange(int(18.0 * FS)) / FS
    exact = sweep_motion(t)
    rec = exact[given] + (0.3 + 0.01 * (t - t[0]) if given == "a" else 2e-6)
    band = kinematics.excited_band(exact["v"], FS)
    assert band[0] == pytest.approx(17.0, abs=1.5) and band[1] == pytest.approx(35.0, abs=1.5)
    got = kinematics.complete({given: rec}, FS, band)
    for want in {"x", "v", "a"} - {given}:
        measured(f"kinematics from {given} only (sweep segment 17–35 Hz, offset and drift): {want} vs analytic, "
                 "RMS error over the excited band / RMS", band_rms_error(got[want], exact[want], band), 5e-3)


def test_periodic_record_is_exact():
    n, fs = 1500, FS
    t = np.arange(4 * n) / fs
    f = np.array([10.0, 17.5, 30.0])  # whole cycles in n samples
    x = sum(1e-3 / (k + 1) * np.sin(2 * np.pi * fk * t + k) for k, fk in enumerate(f))
    a = sum(-(2 * np.pi * fk) ** 2 * 1e-3 / (k + 1) * np.sin(2 * np.pi * fk * t + k) for k, fk in enumerate(f))
    got = kinematics.convert(a, fs, "a", "x", (10.0, 30.0), periodic=True)
    assert np.max(np.abs(got - x)) < 1e-9 * np.max(np.abs(x))


def test_no_motion_is_an_error():
    with pytest.raises(ValueError, match="give one of x, v, a"):
        kinematics.complete({}, FS, (5.0, 40.0))
