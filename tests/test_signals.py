"""Analysis functions against analytic results, and steady-state energy checks on the FMUs."""
import numpy as np
import pytest
import scipy.signal

from pyfit.analysis import signals
from pyfit.analysis.excitation import multisine


def test_psd_of_a_sine_peaks_at_its_frequency_and_integrates_to_its_variance(measured):
    fs, f0, amp = 1000.0, 37.3, 2.5
    t = np.arange(200_000) / fs
    y = amp * np.sin(2 * np.pi * f0 * t + 0.3)
    f, p = signals.welch_psd(y, fs, segment_s=8.0)
    peak, _ = signals.psd_peak(y, fs, segment_s=8.0)
    assert peak == pytest.approx(f0, abs=f[1] - f[0])
    measured("Welch PSD (Hann) of a pure sine: |∫PSD df / variance − 1|", abs(np.trapezoid(p, f) / np.var(y) - 1), 1e-3)


def test_uniform_grid_is_asserted():
    with pytest.raises(ValueError, match="not uniformly sampled"):
        signals.assert_uniform(np.array([0.0, 0.1, 0.25, 0.3]))


def test_frf_of_linear_two_dof_matches_analytic(runner, measured):
    # TwoDOF (a) with the Bouc-Wen element linearised (beta = 0: z = alpha*y2), whole-period multisine
    fs, n = 1000.0, 2000
    u = multisine(n, fs, 2.0, 40.0, 5.0, seed=3)
    periods = 6
    uu = np.append(np.tile(u, periods), u[0])
    t = np.arange(len(uu)) / fs
    res = runner("TwoDOFa").simulate(t[-1], 1 / fs, ["y1"], {"beta": 0.0, "exc_type": 0}, inputs={"f": uu},
                                     input_time=t, tolerance=1e-11)
    assert res.ok
    steady = slice(3 * n, periods * n)  # the first periods carry the transient
    f, H = signals.frf_periodic(uu[steady], res["y1"][steady], fs, n)
    M = np.diag([0.5, 1.0])
    K = np.array([[2500.0, -500.0], [-500.0, 5500.0 + 500.0]])
    C = np.array([[6.0, -1.0], [-1.0, 3.0]])
    w = 2 * np.pi * f
    H_ref = np.array([np.linalg.solve(-wi**2 * M + 1j * wi * C + K, [1.0, 0.0])[0] for wi in w])
    # the input is linear between samples: compare away from anti-resonances (|H| not tiny)
    ok = np.abs(H_ref) > 0.2 * np.median(np.abs(H_ref))
    assert ok.sum() > 0.8 * len(f)
    measured("FRF of TwoDOF (a), β = 0, from whole multisine periods vs the analytic FRF of hand-assembled M, C, K "
             "(away from anti-resonances): max relative error", np.max(np.abs(H[ok] - H_ref[ok]) / np.abs(H_ref[ok])), 0.01)


def test_loop_area_equals_dissipated_energy_per_cycle(runner, measured):
    f_exc = 5.0
    outputs = ["y", "v", "z", "F"]
    res = runner("SDOFBoucWen").simulate(4.0, 1e-4, outputs, {"exc_type": 1, "exc_f_start": f_exc,
                                                             "exc_amplitude": 120.0}, tolerance=1e-10)
    last = signals.last_periods(res.time, {o: res[o] for o in outputs}, f_exc)
    area = signals.loop_area(last["y"], last["F"])  # input work per cycle, integral F dy
    dt = 1e-4
    viscous = np.sum(10.0 * last["v"] ** 2) * dt
    hysteretic = signals.loop_area(last["y"], last["z"])
    assert hysteretic > 0.1 * area
    measured("SDOF stepped sine 5 Hz: |loop area ∮F·dy − (viscous ∮c·v²dt + Bouc-Wen ∮z·dy)| / area",
             abs(area - (viscous + hysteretic)) / area, 0.02)


def test_damper_power_at_constant_velocity_is_positive_and_equals_loop_area(runner, measured):
    outputs = ["F_clamp", "v_clamp", "x_clamp"]
    worst = 0.0
    for f_exc in (8.0, 10.0, 16.0, 20.0, 25.0):  # whole samples per period at 1e-4 s
        res = runner("StockbridgeDamper").simulate(
            6.0, 1e-4, outputs, {"exc_type": 1, "exc_f_start": f_exc, "exc_amplitude": 0.05 / (2 * np.pi * f_exc),
                                 "exc_t_ramp": 0.5}, tolerance=1e-10)
        assert res.ok
        cyc = signals.steady_cycle(res.time, res["F_clamp"], res["v_clamp"], res["x_clamp"], f_exc)
        assert cyc.mean_power > 0
        assert cyc.impedance > 0
        worst = max(worst, abs(cyc.dissipated_energy * f_exc / cyc.mean_power - 1))
    measured("damper at constant clamp velocity, 8–25 Hz: |loop area × f / mean(F_clamp·v_clamp) − 1|", worst, 1e-4)  # trapezoid loop at ωΔt ≤ 0.016: O((ωΔt)²/12)


def test_damper_power_and_impedance_from_a_slow_sweep_match_stepped_sines(runner, measured):
    from pyfit.analysis.excitation import Excitation

    v0, rate = 0.03, 0.25
    exc = Excitation(4, v0, 5.0, 30.0, rate, t_ramp=1.0)
    damper = runner("StockbridgeDamper")
    sweep = damper.simulate(100.0, 1e-3, ["F_clamp", "v_clamp"], {
        "exc_type": 4, "exc_v0": v0, "exc_f_start": 5.0, "exc_f_end": 30.0, "exc_rate": rate, "exc_t_ramp": 1.0})
    at = [12.5, 20.0, 25.0]  # away from the resonances, where a slow sweep is quasi-steady
    power, impedance = signals.sweep_power_impedance(sweep.time, sweep["F_clamp"], sweep["v_clamp"], exc.phase,
                                                     exc.frequency, at)
    dp = dz = 0.0
    for f, p, z in zip(at, power, impedance):
        res = damper.simulate(5.0, 1e-4, ["F_clamp", "v_clamp", "x_clamp"], {
            "exc_type": 1, "exc_f_start": f, "exc_amplitude": v0 / (2 * np.pi * f), "exc_t_ramp": 0.5},
            tolerance=1e-10)
        cyc = signals.steady_cycle(res.time, res["F_clamp"], res["v_clamp"], res["x_clamp"], f)
        assert p > 0
        dp, dz = max(dp, abs(p / cyc.mean_power - 1)), max(dz, abs(z / cyc.impedance - 1))
    measured("damper power along a 0.25 Hz/s constant-velocity sweep vs stepped sines (12.5, 20, 25 Hz): max "
             "relative difference", dp, 0.05)
    measured("damper impedance, the same sweep vs stepped sines: max relative difference", dz, 0.03)


def test_daq_grade_anti_alias_fir_is_flat_where_scipy_default_is_not():
    """The synthetic sensor chain: a Kaiser FIR designed for 0.005 dB ripple stays within it up to 0.7x the
    sensor Nyquist (within 1.2x of it up to 0.8x) and attenuates by as much from the Nyquist on; scipy's
    default decimation FIR (Hamming, 201 taps at q = 10) is +0.024 dB at 58 Hz of a 1 kHz sensor, the tilt
    that biased the SDOF fit by 1.3 %."""
    import scipy.signal

    from pyfit.reference.synthetic import anti_alias_fir

    fs_fine, q = 10000.0, 10
    ripple = 10 ** (0.005 / 20) - 1
    fir = anti_alias_fir(q, 0.005)
    _, h = scipy.signal.freqz(fir, worN=np.linspace(0.0, 400.0, 801), fs=fs_fine)
    assert np.max(np.abs(np.abs(h[:701]) - 1)) <= ripple and np.max(np.abs(np.abs(h) - 1)) <= 1.2 * ripple
    _, h_stop = scipy.signal.freqz(fir, worN=np.linspace(500.0, 4999.0, 2000), fs=fs_fine)
    assert np.max(np.abs(h_stop)) <= 1.2 * ripple
    _, h_default = scipy.signal.freqz(scipy.signal.firwin(201, 1 / q, window="hamming"), worN=[58.0], fs=fs_fine)
    assert 20 * np.log10(abs(h_default[0])) > 0.02


def test_envelope_of_a_modulated_sweep_is_its_amplitude(measured):
    """sim.envelope of A(t) sin(phi(t)) (a 5-40 Hz sweep, A a slow bump) against A(t), away from the ends (the
    Hilbert transform's edge effect), and the envelope residual of an identical simulation is zero."""
    from pyfit.gap.simulate import Record, envelope, envelope_residuals

    fs = 500.0
    t = np.arange(0, 20.0, 1 / fs)
    amp = 1e-3 * (1.0 + 0.5 * np.exp(-((t - 10.0) / 2.0) ** 2))
    y = amp * np.sin(2 * np.pi * (5.0 * t + 0.875 * t**2))
    inner = slice(int(2 * fs), int(18 * fs))
    measured("envelope of an amplitude-modulated 5-40 Hz sweep vs its amplitude: max relative error (2-18 s)",
             np.max(np.abs(envelope(y, fs)[inner] / amp[inner] - 1)), 1e-4)
    rec = Record("r", "", 1.0, fs, {"u": t}, {"y": y}, 0)
    assert np.all(envelope_residuals({"y": y}, rec) == 0.0)
    assert np.sum(envelope_residuals(None, rec) ** 2) == pytest.approx(100.0)  # the penalty: NRMSE 10


def _on_casadi(signal, t):
    """The signal evaluated through a CasADi expression (as the reference integrator sees it)."""
    import casadi as ca

    ts = ca.SX.sym("t")
    return np.array(ca.Function("s", [ts], [signal(ts)]).map(len(t))(t[None, :])).ravel()


def test_a_stepped_sine_dwells_at_each_frequency_with_a_continuous_phase(measured):
    """SteppedSine: in every dwell (after the ramp) the zero-crossing rate is the step's frequency; the signal
    never jumps more than a sine of the highest frequency can between samples; numpy and CasADi agree."""
    from pyfit.analysis.excitation import SteppedSine

    fs, freqs, dwell = 5000.0, tuple(np.geomspace(5.0, 80.0, 8)), 1.0
    s = SteppedSine(freqs, dwell, amplitude=2.0)
    t = np.arange(0.0, len(freqs) * dwell, 1 / fs)
    x = s(t)
    worst = 0.0
    for j, f in enumerate(freqs):
        inside = (t >= j * dwell + (s.t_ramp if j == 0 else 0.0)) & (t < (j + 1) * dwell)
        seg, ts = x[inside], t[inside]
        up = np.flatnonzero((seg[:-1] < 0) & (seg[1:] >= 0))
        crossings = ts[up] - seg[up] * (ts[up + 1] - ts[up]) / (seg[up + 1] - seg[up])  # linear interpolation
        worst = max(worst, abs((len(crossings) - 1) / (crossings[-1] - crossings[0]) / f - 1))
    measured("stepped sine: zero-crossing frequency in each dwell vs the step's, max relative error", worst, 1e-3)
    assert np.max(np.abs(np.diff(x))) <= 2.0 * 2 * np.pi * max(freqs) / fs
    assert np.max(np.abs(_on_casadi(s, t[::50]) - x[::50])) < 1e-12
    assert np.array_equal(s.frequency(np.array([0.5, 1.5, 99.0])), np.array(freqs)[[0, 1, -1]])


def test_band_limited_noise_has_its_rms_its_band_and_a_gaussian_spread(measured):
    """band_noise: the RMS after the ramp is the one asked for (within the scatter of a finite record of
    incommensurate sines), 99 % of the power lies in the band (Welch, Hann), the kurtosis is a Gaussian's;
    numpy and CasADi agree; another seed gives another signal."""
    import scipy.stats

    from pyfit.analysis.excitation import band_noise

    fs, rms = 500.0, 3.0
    n = band_noise(5.0, 80.0, rms, seed=7)
    t = np.arange(0.0, 200.0, 1 / fs)
    x = n(t)[int(n.t_ramp * fs):]
    measured("band-limited noise: RMS over 199 s vs the RMS asked for, relative error",
             abs(np.sqrt(np.mean(x**2)) / rms - 1), 0.03)
    f, p = scipy.signal.welch(x, fs, nperseg=4096)
    measured("band-limited noise: share of the power inside 5-80 Hz (Welch, Hann)",
             p[(f >= 4.5) & (f <= 80.5)].sum() / p.sum(), 0.99, at_least=True)
    measured("band-limited noise: |kurtosis - 3| (Gaussian: 0)", abs(scipy.stats.kurtosis(x, fisher=False) - 3), 0.2)
    assert np.max(np.abs(_on_casadi(n, t[:2000:7]) - n(t[:2000:7]))) < 1e-9 * rms
    assert not np.allclose(band_noise(5.0, 80.0, rms, seed=8)(t[:1000]), n(t[:1000]))


def test_a_channel_held_at_its_range_limit_is_told_from_one_within_its_range():
    """A 13 Hz sine with 1 % noise, sampled at 10 kHz, cut at 0.8 of its amplitude at one or both ends (a range
    limit: the samples beyond it read as the limit): the samples held there are the share of time the sine spends
    beyond 0.8, (pi - 2 asin 0.8) / (2 pi) = 0.2048 per end, to the noise's blur. Within its range, a signal
    gives none, even a slow sine quantized to 16 or 12 bits (its peaks stay on one code for several samples,
    about 2.4 x as many as the code below: the arcsine density at the edge) or a quantized multisine."""
    rng = np.random.default_rng(0)
    n = 200_000
    t = np.arange(n) / 10_000.0
    s = np.sin(2 * np.pi * 13 * t) + rng.normal(0.0, 0.01, n)
    share = (np.pi - 2 * np.arcsin(0.8)) / (2 * np.pi)
    assert signals.clipped_samples(np.clip(s, -2.0, 0.8)) == pytest.approx(share * n, rel=0.01)
    assert signals.clipped_samples(np.clip(s, -0.8, 0.8)) == pytest.approx(2 * share * n, rel=0.01)
    assert signals.clipped_samples(s) == 0
    assert signals.clipped_samples(np.round(0.5 * 32767 * np.sin(2 * np.pi * 5 * t)) / 32767) == 0
    assert signals.clipped_samples(np.round(0.9 * 2047 * np.sin(2 * np.pi * 0.5 * t)) / 2047) == 0
    m = np.tile(multisine(8192, 1000.0, 5.0, 80.0, 1.0, 3), 3) + rng.normal(0.0, 0.01, 3 * 8192)
    assert signals.clipped_samples(m) == 0 and signals.clipped_samples(np.round(m / 1e-3) * 1e-3) == 0
