"""The noise floor of non-periodic broadband records (no periods, no quiet record start, no quiet band):
the local polynomial method against the known sensor noise of a simulated record, and the dataset rule
that sensor noise does not grow with the level while nonlinear distortion does."""
import numpy as np
import scipy.signal as ss

from pyfit.gap import localise
from pyfit.gap.simulate import Record

FS = 750.0
SIGMA = 2e-3  # white sensor noise on the output, in its unit


def levels(distortion: float, seed: int = 3):
    """Three 20 s records of a 40 Hz resonance (Q = 8) driven by noise up to 0.65 x Nyquist (so no quiet band
    above 2 x the excited band), output y + distortion * y^3 plus sensor noise; and each record's true floor."""
    rng = np.random.default_rng(seed)
    n = int(20 * FS)
    b, a = ss.butter(6, 0.65)
    br, ar = ss.iirpeak(40 / (FS / 2), 8)
    recs, truth = [], []
    for j, level in enumerate((1.0, 2.5, 5.0)):
        u = level * ss.lfilter(b, a, rng.standard_normal(n))
        y = ss.lfilter(br, ar, u)
        y = y + distortion * y**3 + SIGMA * rng.standard_normal(n)
        recs.append(Record(f"r{j}", f"level {j}", level, FS, {"u": u}, {"y": y}, 0))
        truth.append(SIGMA / np.sqrt(np.mean(y**2)))
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
