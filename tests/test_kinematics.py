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


def test_a_wide_multisine_read_by_an_accelerometer_keeps_its_lowest_lines(measured):
    # a random-phase odd multisine flat in displacement over 3-75 Hz (its lowest line carries 3e-6 of the
    # highest's acceleration power), two periods read by an accelerometer with white noise at 1e-4 of its RMS:
    # every excited line is a band line, and the noise lines below it are not
    n, periods = 4096, 2
    df = FS / n
    rng = np.random.default_rng(7)
    lines = np.arange(int(3.0 / df), int(75.0 / df) + 1)
    lines = lines[lines % 2 == 1]
    t = np.arange(periods * n) / FS
    phases = rng.uniform(0, 2 * np.pi, lines.size)
    w = 2 * np.pi * lines * df
    x = sum(np.sin(wk * t + p) for wk, p in zip(w, phases))
    a = sum(-wk**2 * np.sin(wk * t + p) for wk, p in zip(w, phases))
    a_meas = a + 1e-4 * np.std(a) * rng.standard_normal(a.size)
    band = kinematics.excited_band(a_meas, FS, samples_per_period=n)
    assert band == pytest.approx((lines[0] * df, lines[-1] * df))
    got = kinematics.complete({"a": a_meas}, FS, band, periodic=True)["x"]
    # measured 0.0071: the accelerometer noise integrated twice on the lines from band[0] / 3 (1 Hz) up, where
    # 1/w^2 amplifies it most. The Welch band (1e-3 of the peak: from 13.5 Hz) loses the lowest lines: 0.14
    measured("displacement integrated from an accelerometer on a 3-75 Hz multisine flat in displacement (noise "
             "1e-4 of the RMS): RMS error / RMS", np.std(got - x) / np.std(x), 0.02)


def test_the_energy_band_and_the_share_below_it_tell_a_drift_from_leakage():
    """A 10-20 Hz sweep from rest over 8 s at 500 Hz: its energy band is 8-22 Hz (its abrupt start and end leak a
    little beyond the swept band), and under half its lower
    edge its Hann-windowed energy share is far below a drift's; the same with a slow random drift of 2 % of its RMS
    added holds about 1e-3 of the energy there (the squared 2 %, and more of the walk's power lies below)."""
    from pyfit.analysis.kinematics import energy_band, share_below

    fs = 500.0
    t = np.arange(int(8 * fs)) / fs
    sweep = np.sin(2 * np.pi * (10 * t + 10 / 16 * t**2))
    lo, hi = energy_band(sweep, fs)
    assert 7.5 <= lo <= 10.0 and 20.0 <= hi <= 22.5
    assert share_below(sweep, fs, lo / 2) < 1e-5
    walk = np.convolve(np.cumsum(np.random.default_rng(3).normal(size=t.size)), np.ones(500), "same")
    drift = 0.02 * np.std(sweep) * (walk - walk.mean()) / np.std(walk)
    assert 2e-4 < share_below(sweep + drift, fs, lo / 2) < 1e-2
