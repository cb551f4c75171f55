"""The default split of a dataset into calibration and held-out files (pyfit.gap.diagnose._load): the files of the
lowest and the highest level calibrate and the levels between are held out (of three levels, the middle one), so that
more levels add held-out evidence, not simulations to every fit; of two levels, the first file calibrates."""
import numpy as np
import pytest

from pyfit.gap import diagnose as dg
from pyfit.io.data import write_measurement


def _dataset(folder, levels, repeats=1):
    """A sweep at each level [N] (a noisy response beside it: the split reads only the levels), written under
    names that do not sort by level, `repeats` files per level."""
    rng = np.random.default_rng(3)
    t = np.arange(2000) / 500.0
    u = np.sin(2 * np.pi * (5.0 + 5.0 * t) * t)
    for level in levels:
        for r in range(repeats):
            write_measurement(folder / f"run{rng.integers(1 << 30)}.csv", "SDOFBoucWen", t,
                              {"f": (level * u, "N", "u")}, {"y": (1e-6 * level * u + 1e-8 * rng.normal(size=t.size),
                                                                   "m", "y")},
                              level=f"amplitude {level:g} N", level_value=float(level))
    return folder


@pytest.mark.parametrize("levels, repeats, calibrated", [((10.0, 25.0, 50.0), 1, {10.0, 50.0}),
                                                          ((5.0, 10.0, 20.0, 40.0, 80.0), 1, {5.0, 80.0}),
                                                          ((10.0, 20.0, 30.0, 40.0), 2, {10.0, 40.0})])
def test_the_lowest_and_highest_levels_calibrate_and_the_levels_between_are_held_out(tmp_path, sdof_system, levels,
                                                                                      repeats, calibrated):
    runner, system = sdof_system
    data = dg._load(_dataset(tmp_path, levels, repeats), system, dg.DiagnoseConfig(), runner)
    assert sorted({r.level_value for r in data.cal}) == sorted(calibrated)
    assert len(data.cal) == 2 * repeats and len(data.held) == (len(levels) - 2) * repeats
    assert sorted({r.level_value for r in data.held}) == sorted(set(levels) - calibrated)


def test_of_two_levels_the_first_file_calibrates(tmp_path, sdof_system):
    runner, system = sdof_system
    data = dg._load(_dataset(tmp_path, (10.0, 20.0)), system, dg.DiagnoseConfig(), runner)
    assert [r.level_value for r in data.cal] == [10.0] and [r.level_value for r in data.held] == [20.0]
