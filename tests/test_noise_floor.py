"""The noise floor of non-periodic broadband records (no periods, no quiet record start, no quiet band):
the local polynomial method against the known sensor noise of a simulated record, and the dataset rule
that sensor noise does not grow with the level while nonlinear distortion does."""
import numpy as np
import pytest
import scipy.signal as ss

from pyfit.gap import localise
from pyfit.gap.simulate import Record

FS = 750.0
SIGMA = 2e-3  # white sensor noise on the output, in its unit


def levels(distortion: float, seed: int = 3, relative_noise: float | None = None):
    """Three 20 s records of a 40 Hz resonance (Q = 8) driven by noise up to 0.65 x Nyquist (so no quiet band
    above 2 x the excited band), output y + distortion * y^3 plus sensor noise (SIGMA, or relative_noise x the
    output's RMS: a sensor range set per level); and each record's true floor."""
    rng = np.random.default_rng(seed)
    n = int(20 * FS)
    b, a = ss.butter(6, 0.65)
    br, ar = ss.iirpeak(40 / (FS / 2), 8)
    recs, truth = [], []
    for j, level in enumerate((1.0, 2.5, 5.0)):
        u = level * ss.lfilter(b, a, rng.standard_normal(n))
        y = ss.lfilter(br, ar, u)
        y = y + distortion * y**3
        sigma = SIGMA if relative_noise is None else relative_noise * np.sqrt(np.mean(y**2))
        y = y + sigma * rng.standard_normal(n)
        recs.append(Record(f"r{j}", f"level {j}", level, FS, {"u": u}, {"y": y}, 0))
        truth.append(sigma / np.sqrt(np.mean(y**2)))
    return recs, truth


def test_local_polynomial_method_finds_the_sensor_noise_of_a_linear_system(measured):
    recs, truth = levels(0.0)
    for r, t in zip(recs, truth):
        var = localise.local_polynomial_noise(r.inputs["u"], r.outputs["y"])
        measured(f"noise floor, linear resonance, {r.level}: |estimate / true sensor noise - 1|",
                 abs(np.sqrt(var) / SIGMA - 1), 0.05)
    est = localise.noise_estimates(recs)
    assert {m for _, m in est.values()} == {"local polynomial, lowest level"}
    for r, t in zip(recs, truth):
        assert abs(est[r.name][0] / t - 1) <= 0.05


def test_distortion_does_not_count_as_noise_at_the_higher_levels(measured):
    recs, truth = levels(0.1)
    high = recs[-1]
    alone = np.sqrt(localise.local_polynomial_noise(high.inputs["u"], high.outputs["y"])) / SIGMA
    assert alone > 5  # on its own, the highest level's distortion looks like noise
    est = localise.noise_estimates(recs)
    for r, t in zip(recs, truth):
        measured(f"noise floor with cubic distortion, {r.level}: |dataset estimate / true floor - 1|",
                 abs(est[r.name][0] / t - 1), 0.1)


def test_noise_that_grows_with_the_level_is_found_by_the_level_scaled_estimate(measured):
    """A sensor range set per level (noise 0.4 % of each record's RMS): the rule for noise that does not grow
    takes the lowest level's noise for all and is low by the level ratio at the others (2.5 and 5); the level
    scaled estimate (what the forward selection measures misfits above) finds each record's floor."""
    recs, truth = levels(0.0, relative_noise=0.004)
    constant = localise.noise_estimates(recs)
    scaled = localise.noise_estimates(recs, level_scaled=True)
    for r, t, ratio in zip(recs, truth, (1.0, 2.5, 5.0)):
        assert abs(constant[r.name][0] * ratio / t - 1) <= 0.1
        measured(f"noise floor growing with the level, {r.level}: |level-scaled estimate / true floor - 1|",
                 abs(scaled[r.name][0] / t - 1), 0.1)


def test_the_level_scaled_estimate_lies_between_the_lowest_level_rule_and_each_records_own():
    """With noise that does not grow and cubic distortion, the level-scaled estimate is never below the lowest
    level rule and never above what a record alone shows (noise and distortion), and at the lowest level it is
    the lowest level rule's, within 10 % of the true floor as above."""
    recs, truth = levels(0.1)
    constant = localise.noise_estimates(recs)
    scaled = localise.noise_estimates(recs, level_scaled=True)
    for r in recs:
        alone = np.sqrt(localise.local_polynomial_noise(r.inputs["u"], r.outputs["y"]) / np.mean(r.outputs["y"] ** 2))
        assert constant[r.name][0] <= scaled[r.name][0] <= alone * (1 + 1e-9)
    assert scaled[recs[0].name][0] == constant[recs[0].name][0]
    assert abs(scaled[recs[0].name][0] / truth[0] - 1) <= 0.1


def swept(fs: float, f_top: float, lead_s: float = 0.0, input_noise: float = 0.0, zero: float = 0.0, seed: int = 5):
    """The acceleration of a 6 s linear displacement sweep from 5 Hz to f_top [Hz] (amplitude growing with the
    frequency squared; a 1 s ramp from its start), after lead_s [s] of rest (the input's sensor noise
    input_noise and zero reading `zero` only), through a 40 Hz resonance (Q = 8; the output's unit) plus white
    sensor noise SIGMA; the record and its true floor (NRMSE)."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(6.0 * fs)) / fs
    f = 5.0 + (f_top - 5.0) / 6.0 * t
    drive = np.minimum(t, 1.0) * (f / f_top) ** 2 * np.sin(2 * np.pi * (5.0 * t + 0.5 * (f_top - 5.0) / 6.0 * t**2))
    u = np.concatenate([np.zeros(int(lead_s * fs)), drive])
    br, ar = ss.iirpeak(40 / (fs / 2), 8)
    y = 50 * ss.lfilter(br, ar, u) + SIGMA * rng.standard_normal(len(u))
    u = u + zero + input_noise * rng.standard_normal(len(u))
    return Record("sweep", "level 1", 1.0, fs, {"u": u}, {"y": y}, 0), SIGMA / np.sqrt(np.mean(y**2))


def test_a_sweep_that_ramps_up_from_its_first_sample_has_no_rest_segment(measured):
    """The ramp's first 0.2 s stays below 1 % of the input's peak while the output already answers it: taken as
    rest, it would count that answer as noise. rest_samples finds next to no rest; the quiet band above the
    sweep gives the floor."""
    rec, truth = swept(750.0, 60.0)
    u, y = rec.inputs["u"], rec.outputs["y"]
    below_one_percent = np.flatnonzero(np.abs(u) > 0.01 * np.abs(u).max())[0]
    assert below_one_percent >= 0.2 * rec.fs
    assert np.std(y[:below_one_percent]) > 1.5 * SIGMA  # the ramp's answer in that lead-up
    assert localise.rest_samples(u, rec.fs) < 0.2 * rec.fs
    var, method = localise.channel_noise([rec])["sweep"]["y"]
    assert method == "quiet band"
    measured("noise floor, sweep ramped from its first sample: |estimate / true floor - 1|",
             abs(np.sqrt(var / np.mean(y**2)) / truth - 1), 0.1)


def test_a_sweep_after_half_a_second_at_rest_takes_its_floor_from_the_rest(measured):
    """0.5 s of rest before the ramp, the input showing only its sensor's noise about a zero reading of 2 (a
    DC accelerometer's 1 g, say): the rest lasts at least until one 50 ms window before the shaker's start (and
    on while the ramp is still below the input's noise) and the output there is the sensor noise (at least 0.45 s,
    338 samples: the estimate's own scatter is at most 4 %)."""
    rec, truth = swept(750.0, 60.0, lead_s=0.5, input_noise=1e-3, zero=2.0)
    assert localise.rest_samples(rec.inputs["u"], rec.fs) >= 0.45 * rec.fs
    var, method = localise.channel_noise([rec])["sweep"]["y"]
    assert method == "pre-excitation"
    measured("noise floor, sweep after 0.5 s at rest: |estimate / true floor - 1|",
             abs(np.sqrt(var / np.mean(rec.outputs["y"] ** 2)) / truth - 1), 0.15)


def test_a_sweep_sampled_below_five_times_its_top_frequency_takes_the_quiet_band_from_1_25x(measured):
    """A sweep to 110 Hz sampled at 500 Hz (a damper's test band at a lab's usual rate): no band from 2x its top
    frequency below 0.4 fs, but one from 1.25x; the local polynomial method, the fallback, is far above the
    sensor noise on a 6 s sweep through a sharp resonance."""
    rec, truth = swept(500.0, 110.0)
    y = rec.outputs["y"]
    var, method = localise.channel_noise([rec])["sweep"]["y"]
    assert method == "quiet band"
    measured("noise floor, sweep to 0.22 fs: |quiet band from 1.25x / true floor - 1|",
             abs(np.sqrt(var / np.mean(y**2)) / truth - 1), 0.1)
    assert np.sqrt(localise.local_polynomial_noise(rec.inputs["u"], y) / np.mean(y**2)) > 3 * truth


def test_the_input_sensors_noise_alone_seldom_ends_a_rest_early(measured):
    """2,000 records of 20 windows of 16 samples (the shortest window) of the input sensor's white noise, then a
    sine 1,000 times as large: the share whose rest ends before the window next to the sine's start (the last
    one left out). The RMS of 16 samples scatters by about 18 %, so a window reaches twice that of the windows
    before it by chance now and then (the share measured is in results/tests.md); the 2 % allowed is about four
    binomial standard deviations of 2,000 records above a 1 % share."""
    rng = np.random.default_rng(11)
    fs = 320.0  # 50 ms = 16 samples
    drive = 1e3 * np.sin(2 * np.pi * 7.0 * np.arange(320) / fs)
    rests = [localise.rest_samples(np.concatenate([rng.standard_normal(320), drive]), fs) for _ in range(2000)]
    assert max(rests) == 19 * 16
    measured("rest of 20 windows of input noise before a sine, ended early by the noise: share of records",
             np.mean(np.array(rests) < 19 * 16), 0.02)



def test_the_where_bands_of_a_sweep_from_0_hz_hold_its_resonance_and_the_octaves_below_it():
    """A 0-40 Hz linear sweep excites down to a fraction of a hertz: the default bands start at the top / BAND_SPAN
    (not at that fraction), log-spaced, so the 21 Hz resonance has four bands below it; a 5-40 Hz sweep keeps
    its bands from 0.8 x its lowest excited line."""
    fs, T = 1024.0, 20.0
    t = np.arange(int(T * fs)) / fs
    br, ar = ss.iirpeak(21.0 / (fs / 2), 30)
    bands, lowest = {}, {}
    for f0 in (0.0, 5.0):
        u = np.clip(t / 0.5, 0, 1) * np.sin(2 * np.pi * (f0 * t + (40.0 - f0) / (2 * T) * t**2))
        recs = [Record(f"r{j}", "", j, fs, {"u": a * u}, {"y": ss.lfilter(br, ar, a * u)}, 0) for j, a in
                enumerate((1.0, 2.0))]
        bands[f0], lowest[f0] = localise.default_bands(recs), localise.excited_range(recs)[0]
    top = bands[0.0][-1][1]
    assert lowest[0.0] < 0.5 and 1.2 * 40.0 <= top <= 1.2 * 42.0
    assert bands[0.0][0][0] == pytest.approx(top / localise.BAND_SPAN, rel=1e-12)
    assert np.allclose([b / a for a, b in bands[0.0]], localise.BAND_SPAN ** (1 / 8))
    assert sum(a <= 21.0 <= b for a, b in bands[0.0]) == 1 and bands[0.0][3][1] < 21.0
    assert 4.0 < bands[5.0][0][0] == pytest.approx(0.8 * lowest[5.0], rel=1e-12)
