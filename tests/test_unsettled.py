"""A periodic record whose response does not repeat from one period to the next (chaos, a subharmonic, a record
still settling) is set aside by the default split: no simulation follows it sample by sample, and calibrating
on it pulls every parameter off. Checked on Ueda's driven Duffing oscillator x'' + 0.05 x' + x^3 = B cos t
(integrated here with scipy: periodic at B = 0.3 and 1, chaotic at B = 7.5), against sensor noise alone, and
on a lab-style dataset read by the diagnosis."""
import tomllib

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from gap_cases import CI
from pyfit.gap import datasets, localise
from pyfit.gap import diagnose as dg
from pyfit.gap.simulate import Record

SPP, PERIODS, SETTLE = 64, 6, 150  # samples per forcing period, periods recorded, periods left to settle
NOISE = 0.01  # sensor noise, relative to each record's RMS


def ueda(level: float, index: int, noise: float = NOISE) -> Record:
    """PERIODS periods of Ueda's oscillator forced at B = `level` (after SETTLE periods; the damping's time
    constant is 40 s, the settling 942 s), with white sensor noise of `noise` x the response's RMS."""
    t = np.arange((SETTLE + PERIODS) * SPP) * 2 * np.pi / SPP
    sol = solve_ivp(lambda s, x: [x[1], -0.05 * x[1] - x[0] ** 3 + level * np.cos(s)], (0, t[-1]), [0.0, 0.0],
                    t_eval=t, method="DOP853", rtol=1e-9, atol=1e-11)
    y = sol.y[0][SETTLE * SPP:] - np.mean(sol.y[0][SETTLE * SPP:])
    y = y + noise * np.sqrt(np.mean(y**2)) * np.random.default_rng(index).standard_normal(len(y))
    return Record(f"B{level:g}", f"B = {level:g}", level, SPP / (2 * np.pi),
                  {"u": level * np.cos(t[SETTLE * SPP:])}, {"y": y}, SPP)


def test_a_chaotic_level_is_set_aside_and_the_periodic_ones_are_not():
    recs = [ueda(b, i) for i, b in enumerate((0.3, 1.0, 7.5))]
    floors = localise.noise_estimates(recs)
    for r in recs[:2]:  # the period scatter of a periodic response is the sensor noise
        assert floors[r.name][0] == pytest.approx(NOISE, rel=0.15)
    aside = localise.unsettled(recs)
    assert list(aside) == ["B7.5"]
    scatter, lower = aside["B7.5"]
    assert scatter > 0.3 and lower == pytest.approx(NOISE, rel=0.15)


def test_sensor_noise_alone_sets_nothing_aside():
    """Noise far above the threshold (8 % of the response's RMS) at the lowest level, falling relative to
    the response at the higher ones (a fixed noise), or the same share at every level (a range set per
    level): nothing is set aside."""
    fixed = [ueda(b, i, noise=0.08 * (0.3 / b) ** (1 / 3)) for i, b in enumerate((0.3, 1.0, 4.0))]
    ranged = [ueda(b, i, noise=0.08) for i, b in enumerate((0.3, 1.0, 4.0))]
    assert localise.noise_estimates(fixed)["B0.3"][0] > localise.UNSETTLED_NRMSE
    assert localise.unsettled(fixed) == {} and localise.unsettled(ranged) == {}


def not_repeating(path, share: float, rng):
    """The file's output plus a tone `share` x the output's RMS that turns half a cycle more than whole ones
    in a period of the excitation (it changes sign from one period to the next)."""
    sidecar = tomllib.loads(path.with_suffix(".toml").read_text())
    period_s = sidecar["excitation"]["samples_per_period"] / sidecar["sample_rate_hz"]
    rows = np.loadtxt(path, delimiter=",", skiprows=1)
    header = path.read_text().splitlines()[0]
    t, y = rows[:, 0], rows[:, 2]
    f = (np.floor(10 * period_s) + 0.5) / period_s  # about 10 Hz, inside the excited band
    rows[:, 2] = y + share * np.std(y) * np.sqrt(2) * np.sin(2 * np.pi * f * t + rng.uniform(0, 2 * np.pi))
    np.savetxt(path, rows, delimiter=",", header=header, comments="", fmt="%.10g")


def test_the_diagnosis_splits_the_other_files_and_says_why(tmp_path, sdof_system):
    runner, sdof = sdof_system
    rng = np.random.default_rng()
    data = datasets.write_dataset(tmp_path / "data", datasets.SDOF, "none", seed=int(rng.integers(1 << 31)),
                                  periods=2)
    files = sorted(data.glob("*.csv"))  # level1_10N, level2_25N, level3_50N
    not_repeating(files[2], rng.uniform(0.2, 0.5), rng)
    loaded = dg._load(data, sdof, CI, runner)
    records, cal, held, aside = loaded.records, loaded.cal, loaded.held, loaded.aside
    assert list(aside) == [files[2].stem] and aside[files[2].stem][0] > 0.15
    assert [r.name for r in cal] == [files[0].stem] and [r.name for r in held] == [files[1].stem]
    assert files[2].stem not in [r.name for r in records]
    # files the user names to calibrate on are the user's: nothing is set aside
    named = dg.DiagnoseConfig(calibration=[files[0].stem, files[2].stem])
    assert dg._load(data, sdof, named, runner).aside == {}
    not_repeating(files[1], 0.3, rng)  # two of three files unsettled: one error naming both
    with pytest.raises(dg.DiagnoseError, match=f"{files[1].stem}, {files[2].stem} does not repeat"):
        dg._load(data, sdof, CI, runner)
