"""The rate a diagnosis works at (pyfit.gap.rate): files sampled far faster than their excitation needs are decimated
to at least RATE_FACTOR times the highest excited frequency after a zero-phase anti-alias filter
(pyfit.analysis.signals.decimated).

The filter is checked against analytic signals: whole periods of a multisine come back exactly on the coarser grid,
a sine in the flat passband (below 0.6 of the new Nyquist frequency) within 1e-4 of its amplitude, a sine above the
new Nyquist frequency attenuated by at least 100 dB. A diagnosis of an SDOF with a random cubic spring recorded by
the CasADi reference at a random rate 42-55 times its sweep's top frequency is analysed at half that rate, names the
spring and recovers its strength within 2 % and the linear stiffness within 1 %.

The FMU's drive grid follows the analysis rate (drive_upsample): a file faster than REFERENCE_HZ is driven on as many
grid points a second as a file at that rate, and meets a closed-form response at least as well as one."""
import dataclasses

import numpy as np
import pytest

from gap_cases import CI
from pyfit.analysis.signals import DECIMATION_TAPS, decimated
from pyfit.gap import datasets
from pyfit.gap import diagnose as dg
from pyfit.gap import simulate as sim
from pyfit.gap.rate import RATE_FACTOR, REFERENCE_HZ, AnalysisRate, analysis_rate, at_rate, drive_upsample
from pyfit.io.data import read_dataset, write_measurement
from pyfit.runtime.drive import drive
from test_spline_drive import LINEAR, forced_from_rest


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
    rate = rep.analysis_rate
    assert rate["factor"] == 2 and rate["file_hz"] == pytest.approx(fs)
    assert fs / rate["factor"] >= RATE_FACTOR * rate["top_hz"] and 58.0 <= rate["top_hz"] <= 63.0  # the sweep's 60 Hz
    assert rate["drive_upsample"] == 2  # 2.6-3.4 kHz grid: at least the 2 kHz the SDOF family's 500 Hz files have
    assert rep.chosen_name == "cubic_stiffness", rep.sentence
    fitted = rep.ranking[0].params
    measured("SDOF recorded at 42-55 x its top frequency, decimated: |k3'/k3 - 1|",
             abs(fitted["k3"] / truth["k3"] - 1.0), 0.02)
    measured("SDOF recorded at 42-55 x its top frequency, decimated: |k'/k - 1|", abs(fitted["k"] / truth["k"] - 1.0),
             0.01)
    assert f"decimated by {rate['factor']}" in (root / "out" / "report.md").read_text()


def test_the_drive_grid_keeps_the_familys_points_per_second_and_per_excited_cycle():
    """drive_upsample: a file at REFERENCE_HZ keeps its family's grid whatever its excitation (the grid the
    campaigns calibrated on); a faster one keeps as many grid points a second, or per sample of twice its highest
    excited frequency when that is the more; a slower one keeps the family's multiple."""
    for upsample in (2, 4):
        for top in np.linspace(1.0, REFERENCE_HZ / 2, 50):
            assert drive_upsample(upsample, AnalysisRate(REFERENCE_HZ, 1, float(top), RATE_FACTOR)) == upsample
        assert drive_upsample(upsample, AnalysisRate(200.0, 1, 40.0, RATE_FACTOR)) == upsample
    assert drive_upsample(2, AnalysisRate(1000.0, 1, 40.0, RATE_FACTOR)) == 1  # a damper file at 1 kHz
    assert drive_upsample(4, AnalysisRate(1000.0, 1, 80.0, RATE_FACTOR)) == 2  # an SDOF one: 2 kHz as at 500 Hz
    assert drive_upsample(2, AnalysisRate(2500.0, 3, 40.0, RATE_FACTOR)) == 2  # decimated to 833 Hz: 1.67 kHz
    # broadband noise to 0.65 of the Nyquist frequency at 10 kHz: 4 points per sample of 6.5 kHz
    assert drive_upsample(4, AnalysisRate(1e4, 1, 3250.0, RATE_FACTOR)) == 3


@pytest.mark.parametrize("smooth, upsample, tolerance", [(True, 2, sim.SPLINE_TOLERANCE), (False, 4, sim.TOLERANCE)],
                         ids=["spline (damper)", "lines (SDOF)"])
def test_a_faster_file_on_its_coarser_grid_meets_the_closed_form_as_well(runner, measured, smooth, upsample,
                                                                          tolerance):
    """A linear oscillator (test_spline_drive) forced at 35 Hz from rest, its force sampled at REFERENCE_HZ and at
    twice that: the faster file driven on the grid drive_upsample gives it (as many points a second, half as many
    per sample) meets the closed form at least as well as the slower file on its family's grid, for either drive."""
    m, c, k, f0, w = 2.0, 2 * 0.02 * np.sqrt(1.2e5 * 2.0), 1.2e5, 10.0, 2 * np.pi * 35.0
    fmu, params = runner("SDOFBoucWen"), {**LINEAR, "m": m, "c": c, "k": k}

    def error(fs, grid):
        t = np.arange(int(2 * fs) + 1) / fs
        exact = forced_from_rest(m, c, k, f0, w, t)
        y = drive(fmu, {"u": f0 * np.sin(w * t)}, fs, ["y"], params, grid, tolerance=tolerance,
                  smooth_inputs=smooth).values["y"]
        return np.sqrt(np.mean((y - exact) ** 2) / np.mean(exact ** 2))

    grid = drive_upsample(upsample, AnalysisRate(2 * REFERENCE_HZ, 1, 35.0, RATE_FACTOR))
    assert grid == upsample // 2
    slow, fast = error(REFERENCE_HZ, upsample), error(2 * REFERENCE_HZ, grid)
    # (measured: the spline 5.9e-5 at 500 Hz, 8.1e-6 at 1 kHz; the lines 1.06e-3 and 1.01e-3, the same grid's lines)
    measured(f"linear oscillator forced at 35 Hz, {'spline' if smooth else 'lines'}: NRMSE against the closed form "
             f"of a {2 * REFERENCE_HZ:g} Hz file on {grid} grid point(s) per sample over a {REFERENCE_HZ:g} Hz "
             f"file's on {upsample}", fast / slow, 1.0)


def test_a_level_recorded_faster_is_brought_to_the_dataset_s_rate(tmp_path, sdof_system):
    """Three levels of a linear SDOF's response to a 5-80 Hz sweep (scipy lsim at 1 kHz, independent of the FMU),
    the middle one written at 1 kHz and the others at every second sample (500 Hz): the 1 kHz file is decimated to
    500 Hz after the anti-alias filter (80 Hz lies in its flat passband, within 1e-4: its own 500 Hz samples
    are met to that), the report names it; a rate that is no whole multiple of the slowest is refused."""
    import scipy.signal

    from pyfit.gap.report import _rate_lines

    runner, system = sdof_system
    t = np.arange(6000) / 1000.0
    u = np.sin(2 * np.pi * (5.0 + 6.25 * t) * t)
    _, y, _ = scipy.signal.lsim(([1.0 / 2.0], [1.0, 5.0, 5e4]), u, t)
    for level, step in ((10.0, 2), (25.0, 1), (50.0, 2)):
        write_measurement(tmp_path / f"L{level:g}.csv", "SDOFBoucWen", t[::step], {"F": (level * u[::step], "N", "u")},
                          {"y": (level * y[::step], "m", "y")}, level_value=level)
    data = dg._load(tmp_path, system, dg.DiagnoseConfig(), runner)
    assert data.rate.file_hz == pytest.approx(500.0) and data.recorded_hz == {"L25": pytest.approx(1000.0)}
    held = data.held[0]
    assert held.name == "L25" and held.fs == pytest.approx(500.0)
    want = 25.0 * y[::2][: len(held.outputs["y"])]
    assert np.max(np.abs(held.outputs["y"] - (want - np.mean(want)))) < 1e-4 * np.max(np.abs(want))
    assert "L25 (1000 Hz, decimated by 2)" in "".join(_rate_lines({"file_hz": 500.0, "recorded_hz": data.recorded_hz}))
    write_measurement(tmp_path / "L25.csv", "SDOFBoucWen", t[::4] * 4 / 3, {"F": (25.0 * u[::4], "N", "u")},
                      {"y": (25.0 * y[::4], "m", "y")}, level_value=25.0)  # 187.5 Hz: 500 Hz is no whole multiple
    with pytest.raises(dg.DiagnoseError, match=r"L10.toml: sample_rate_hz = 500 but L25.csv has 187.5; allowed: one "
                                               r"rate, or rates that are whole multiples of the slowest"):
        dg._load(tmp_path, system, dg.DiagnoseConfig(), runner)
