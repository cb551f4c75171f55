"""The default split of a dataset into calibration and held-out files (pyfit.gap.diagnose.default_calibration, through
_load): the files of the lowest and the highest level calibrate and the levels between are held out (of three levels,
the middle one), so that more levels add held-out evidence, not simulations to every fit; of two levels, the files of
the lower calibrate; of one level in several files, every other one."""
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


@pytest.mark.parametrize("repeats", [1, 3])
def test_of_two_levels_the_lower_level_s_files_calibrate(tmp_path, sdof_system, repeats):
    """Two levels in one file each, or in several (a sweep up and down, a stepped sine's frequencies)."""
    runner, system = sdof_system
    data = dg._load(_dataset(tmp_path, (10.0, 20.0), repeats), system, dg.DiagnoseConfig(), runner)
    assert [r.level_value for r in data.cal] == [10.0] * repeats
    assert [r.level_value for r in data.held] == [20.0] * repeats


@pytest.mark.parametrize("files, calibrated", [(2, [0]), (3, [0, 2]), (6, [0, 2, 4])])
def test_of_one_level_in_several_files_every_other_one_calibrates(files, calibrated):
    """One level in several files (a stepped sine's frequencies, repeated runs): the calibration spans them, so
    that a nominal is not fitted to one frequency and judged at all the others."""

    class Rec:
        def __init__(self, i):
            self.name, self.level_value = f"f{i}", 10.0

    records = [Rec(i) for i in range(files)]
    assert [r.name for r in dg.default_calibration(records)] == [f"f{i}" for i in calibrated]


@pytest.mark.slow
def test_a_stepped_sine_recorded_a_file_per_frequency_is_diagnosed(tmp_path, fmu_dir, measured):
    """Two levels (15, 45 N) of six sines (0.6-1.5 x the resonance) in a file each, written by the CasADi reference
    with a cubic spring of a strength drawn log-uniformly over a decade, 0.5 % noise on force and displacement.
    The lower level's six files calibrate (one file, one frequency, could not place the resonance) and the
    spring is named with its strength."""
    from pyfit.analysis.excitation import Excitation
    from pyfit.gap import datasets
    from pyfit.reference.synthetic import SyntheticSpec, simulate_truth

    rng = np.random.default_rng(5)
    k3 = float(np.exp(rng.uniform(np.log(5e7), np.log(5e8))))
    truth = {**datasets.SDOF.linear, "k3": k3}
    for level in (15.0, 45.0):
        for f in np.round(35.6 * np.geomspace(0.6, 1.5, 6), 2):
            t, y, u = simulate_truth(SyntheticSpec("SDOFBoucWen", Excitation(1, level, f, f, t_ramp=0.5), 4.0, 500.0,
                                                   ["y"], truth, seed=int(f * 100)))
            noisy = {k: v + 0.005 * np.std(v) * rng.standard_normal(len(t)) for k, v in (("y", y["y"]), ("u", u["u"]))}
            write_measurement(tmp_path / "data" / f"L{level:g}N_f{f:g}Hz.csv", "SDOFBoucWen", t,
                              {"F": (noisy["u"], "N", "u")}, {"y": (noisy["y"], "m", "y")}, level=f"{level:g} N",
                              level_value=level, excitation={"kind": "sine", "frequency_hz": float(f)})
    rep = dg.diagnose("sdof", tmp_path / "data", tmp_path / "out", fmu_dir=fmu_dir, workers=2)
    assert list(rep.calibration_files) == sorted(p.stem for p in (tmp_path / "data").glob("L15N_*.csv"))
    assert rep.chosen == ("cubic_stiffness",), rep.sentence
    fitted = next(r for r in rep.ranking if r.effect == "cubic_stiffness").params["k3"]
    measured("stepped sine in a file per frequency (SDOF, cubic spring drawn over a decade): fitted k3 vs the "
             "truth, relative", abs(fitted / k3 - 1), 0.03)


@pytest.mark.slow
def test_one_continuous_record_of_three_levels_cut_by_segments_is_diagnosed(tmp_path, fmu_dir, measured):
    """One record holding three levels one after the other (a 5-80 Hz log sweep at 10, 25 then 50 N, 6 s each, the
    response carried over between them: the later segments do not start at rest), simulated by the CasADi
    reference with a cubic spring drawn log-uniformly over a decade, written as one file whose sidecar cuts it
    into three [[segments]]: the ends calibrate, the middle is held out, and the spring is named with its
    strength."""
    from pyfit.gap import datasets
    from pyfit.reference import integrate, models

    rng = np.random.default_rng(11)
    k3 = float(np.exp(rng.uniform(np.log(5e7), np.log(5e8))))
    fs, over, stage, f0, f1 = 500.0, 10, 6.0, 5.0, 80.0
    t_fine = np.arange(int(3 * stage * fs * over)) / (fs * over)
    ts = np.mod(t_fine, stage)
    amp = np.select([t_fine < stage, t_fine < 2 * stage], [10.0, 25.0], 50.0)
    u = amp * np.sin(2 * np.pi * f0 * stage / np.log(f1 / f0) * (np.exp(ts / stage * np.log(f1 / f0)) - 1))
    y = integrate.simulate_cvodes(models.by_name("SDOFBoucWen"), t_fine, params={**datasets.SDOF.linear, "k3": k3},
                                  inputs={"u": u})["y"][::over]
    y = y + 0.003 * np.std(y[: int(stage * fs)]) * rng.standard_normal(len(y))
    path = write_measurement(tmp_path / "data" / "run.csv", "SDOFBoucWen", t_fine[::over], {"F": (u[::over], "N", "u")},
                             {"y": (y, "m", "y")})
    side = path.with_suffix(".toml")
    side.write_text(side.read_text() + "".join(
        f"[[segments]]\nfrom_s = {k * stage}\nto_s = {(k + 1) * stage}\nlevel = \"{a:g} N\"\nlevel_value = {a}\n"
        for k, a in enumerate((10.0, 25.0, 50.0))))
    rep = dg.diagnose("sdof", tmp_path / "data", tmp_path / "out", fmu_dir=fmu_dir, workers=2, progress=False)
    assert (rep.calibration_files, rep.held_out_files) == (("run#1", "run#3"), ("run#2",))
    assert rep.chosen == ("cubic_stiffness",), rep.sentence
    fitted = next(r for r in rep.ranking if r.effect == "cubic_stiffness").params["k3"]
    measured("one record of three levels cut by [[segments]] (SDOF, cubic spring drawn over a decade): fitted k3 vs "
             "the truth, relative", abs(fitted / k3 - 1), 0.03)
