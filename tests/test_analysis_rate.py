"""The rate a diagnosis works at (pyfit.gap.rate): files sampled far faster than their excitation needs are decimated
to at least RATE_FACTOR times the highest excited frequency after a zero-phase anti-alias filter
(pyfit.analysis.signals.decimated).

The filter is checked against analytic signals: whole periods of a multisine come back exactly on the coarser grid,
a sine in the flat passband (below 0.6 of the new Nyquist frequency) within 1e-4 of its amplitude, a sine above the
new Nyquist frequency attenuated by at least 100 dB. A diagnosis of an SDOF with a random cubic spring recorded by
the CasADi reference at a random rate 42-55 times its sweep's top frequency is analysed at half that rate, names the spring and recovers its strength within 2 % and the linear stiffness within 1 %."""
import dataclasses

import numpy as np
import pytest

from gap_cases import CI
from pyfit.analysis.signals import DECIMATION_TAPS, decimated
from pyfit.gap import datasets
from pyfit.gap import diagnose as dg
from pyfit.gap.rate import RATE_FACTOR, analysis_rate, at_rate
from pyfit.io.data import read_dataset, write_measurement


def test_whole_periods_decimate_exactly():
    rng = np.random.default_rng(7)
    n, q = 4096, 4
    k = np.arange(n)
    lines = rng.choice(np.arange(1, n // (2 * q)), 12, replace=False)  # below the new Nyquist line
    amps, phases = rng.uniform(0.2, 1.0, 12), rng.uniform(0, 2 * np.pi, 12)
    inside = sum(a * np.cos(2 * np.pi * j * k / n + p) for j, a, p in zip(lines, amps, phases))
    above = 0.5 * np.cos(2 * np.pi * (n // (2 * q) + 37) * k / n)  # above it: removed, not folded back
    assert np.max(np.abs(decimated(inside + above, q, periodic=True) - inside[::q])) < 1e-12


@pytest.mark.parametrize("q", [2, 3, 5])
def test_the_anti_alias_filter_is_flat_below_and_stops_above_the_new_nyquist(q):
    fs = 1000.0 * q
    t = np.arange(int(20 * fs)) / fs
    edge = 200  # samples at each end where the filter sees past the record
    for f in (0.05, 0.3, 0.6):  # of the new Nyquist frequency (500 Hz)
        y = np.sin(2 * np.pi * f * 500.0 * t + 0.3)
        assert np.max(np.abs(decimated(y, q) - y[::q])[edge:-edge]) < 1e-4, f
    y = np.sin(2 * np.pi * 1.05 * 500.0 * t)
    assert np.sqrt(np.mean(decimated(y, q)[edge:-edge] ** 2)) < 1e-5 * np.sqrt(0.5)


def test_a_multisine_keeps_whole_periods(tmp_path):
    """The factor divides the samples per period, which shrink with it."""
    fs, spp = 6000.0, 3 * 1022  # 2 x 3 x 7 x 73 samples: a factor of 4 would split a period
    t = np.arange(2 * spp) / fs
    u = sum(np.sin(2 * np.pi * j * fs / spp * t) for j in range(5, 35))  # lines up to 66.5 Hz
    for i in (1, 2):
        write_measurement(tmp_path / f"level{i}.csv", "SDOFBoucWen", t, {"f": (i * u, "N", "u")},
                          {"y": (1e-6 * i * u, "m", "y")}, level_value=float(i),
                          excitation={"kind": "multisine", "samples_per_period": spp})
    ms = read_dataset(tmp_path)
    rate = analysis_rate(ms)
    assert rate.top_hz == pytest.approx(34 * fs / spp)
    assert fs / (4 * RATE_FACTOR * rate.top_hz) >= 1  # 4 would keep the ratio but splits a period
    assert rate.factor == 3 and rate.hz == 2000.0
    assert analysis_rate([ms[0], dataclasses.replace(ms[1], t=ms[1].t[:-7])]).factor == 1  # not whole periods
    m = at_rate(ms[0], rate.factor)
    assert m.excitation["samples_per_period"] == 1022 and len(m.t) == 2044 and m.sample_rate_hz == pytest.approx(2000)


def test_a_record_that_is_not_periodic_loses_only_the_samples_the_filter_reaches_past_its_end(tmp_path):
    fs = 5000.0
    t = np.arange(int(8 * fs)) / fs
    f = 5.0 + 5.0 * t  # a sweep from rest, 5-45 Hz, stopped at full amplitude
    u = np.sin(2 * np.pi * np.cumsum(f) / fs) * np.minimum(t, 1.0)
    for i in (1, 2):
        write_measurement(tmp_path / f"level{i}.csv", "SDOFBoucWen", t, {"f": (i * u, "N", "u")},
                          {"y": (1e-6 * i * u, "m", "y")}, level_value=float(i))
    ms = read_dataset(tmp_path)
    rate = analysis_rate(ms)
    assert 45.0 <= rate.top_hz <= 47.0 and rate.factor == 5
    m = at_rate(ms[0], rate.factor)
    assert len(m.t) == len(t) // 5 - DECIMATION_TAPS and m.sample_rate_hz == pytest.approx(1000.0)
    # what is kept is the sweep itself: within 1e-4 of its amplitude from the first sample to the last
    assert np.max(np.abs(m.values["f"] - u[::5][:len(m.t)])) < 1e-4


@pytest.fixture(scope="module")
def fast_sdof(tmp_path_factory):
    """A random SDOF (m, c, k within 0.7-1.4 of the family's) with a random cubic spring (0.5-2 x the family's
    reference), swept over 5-60 Hz and recorded by the CasADi reference at a random 2600-3400 Hz."""
    rng = np.random.default_rng(20261206)
    base = {"m": 2.0 * rng.uniform(0.7, 1.4), "c": 10.0 * rng.uniform(0.7, 1.4), "k": 1e5 * rng.uniform(0.7, 1.4)}
    k3 = datasets.SDOF.withheld["cubic_stiffness"]["k3"] * float(np.exp(rng.uniform(np.log(0.5), np.log(2.0))))
    family = dataclasses.replace(datasets.SDOF, fs=float(rng.uniform(2600.0, 3400.0)), band_hz=(5.0, 60.0))
    root = tmp_path_factory.mktemp("fast")
    data = datasets.write_dataset(root / "data", family, "cubic_stiffness", seed=int(rng.integers(1 << 30)),
                                  style=datasets.LabStyle("sweep", record_s=8.0), base=base,
                                  truth={**datasets.SDOF.withheld["cubic_stiffness"], "k3": k3})
    return root, data, {**base, "k3": k3}, family.fs


def test_a_fast_record_is_diagnosed_at_a_lower_rate_with_the_same_result(fast_sdof, fmu_dir, measured):
    root, data, truth, fs = fast_sdof
    rep = dg.diagnose("sdof", data, root / "out", CI, fmu_dir, workers=2, progress=False)
    rate = rep["analysis_rate"]
    assert rate["factor"] == 2 and rate["file_hz"] == pytest.approx(fs)
    assert fs / rate["factor"] >= RATE_FACTOR * rate["top_hz"] and 58.0 <= rate["top_hz"] <= 63.0  # the sweep's 60 Hz
    assert rep["chosen_effect"] == "cubic_stiffness", rep["verdict"]
    fitted = rep["ranking"][0]["params"]
    measured("SDOF recorded at 42-55 x its top frequency, decimated: |k3'/k3 - 1|",
             abs(fitted["k3"] / truth["k3"] - 1.0), 0.02)
    measured("SDOF recorded at 42-55 x its top frequency, decimated: |k'/k - 1|", abs(fitted["k"] / truth["k"] - 1.0),
             0.01)
    assert f"decimated by {rate['factor']}" in (root / "out" / "report.md").read_text()
