"""The noise floor of non-periodic broadband records (no periods, no quiet record start, no quiet band):
the local polynomial method against the known sensor noise of a simulated record, and the dataset rule
that sensor noise does not grow with the level while nonlinear distortion does."""
import numpy as np
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
