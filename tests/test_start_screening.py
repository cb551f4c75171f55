"""attribute.run_fit with many starts: they are ranked on the FMU's input grid at the sensor rate (upsample 1)
first, and only the best of each basin is scored at the refit's upsample; the two grids order the SDOF loop's
starts alike."""
import numpy as np
import pytest
import scipy.stats

from gap_cases import CI, case
from pyfit.gap import attribute
from pyfit.gap import diagnose as dg


class _Captured(Exception):
    pass


class _NoRunner:
    def __init__(self, fmu):
        pass

    def close(self):
        pass


def test_many_starts_are_ranked_coarsely_and_the_best_of_each_basin_scored_finely(monkeypatch):
    """A quadratic misfit about a point in basin 'b': every start is scored once at upsample 1, only the start,
    the best SCREEN_KEPT of each basin and the probed start again at the task's upsample, and the descent reaches
    the minimum from there."""
    truth = np.array([0.3, 0.7])
    calls = []

    def stacked(runner, records, params, upsample, lead_periods, pool=None, of=None):
        calls.append(upsample)
        x = np.array([params["a"], params["b"]])
        return (x - truth) * (1.0 + 0.01 * (upsample == 1))  # the coarse grid scales the misfit: same order

    monkeypatch.setattr(attribute, "_stacked", stacked)
    monkeypatch.setattr(attribute, "FmuRunner", _NoRunner)
    grid = [{"a": a, "b": b} for a in np.linspace(0.0, 1.0, 9) for b in np.linspace(0.0, 1.0, 9)]  # 81 starts
    task = attribute.FitTask("x.fmu", ("r",), {}, {"a": 0.5, "b": 0.5}, {"a": (0.0, 1.0), "b": (0.0, 1.0)}, "e",
                             2, 40, 4, alternatives=tuple(grid), basin=_half, continuation=False,
                             probed=({"a": 1.0, "b": 0.0},))
    fit = attribute.run_fit(task)
    n = 1 + len(grid) + 1
    assert n > attribute.SCREEN_FROM
    assert calls[:n] == [1] * n  # every start on the coarse grid first
    fine = calls[n:].index(4)
    # then the start, the probed one and the best three of each of the two basins ('a' below or above 0.5)
    assert calls[n + fine:n + fine + 2 + 2 * attribute.SCREEN_KEPT] == [4] * (2 + 2 * attribute.SCREEN_KEPT)
    assert 1 not in calls[n:]
    assert fit.params["a"] == pytest.approx(0.3, abs=1e-6) and fit.params["b"] == pytest.approx(0.7, abs=1e-6)
    assert fit.evaluations == len(calls)


def _half(values):
    return values["a"] < 0.5


def test_the_loop_starts_rank_alike_at_the_sensor_rate_and_upsampled(tmp_path, fmu_dir, monkeypatch):
    """The SDOF hysteresis refit's starts on the withheld-hysteresis dataset (CasADi reference): their
    calibration misfits at upsample 1 and at the refit's upsample (4) have a rank correlation above 0.99, and
    each basin's best start at upsample 4 is among its best SCREEN_KEPT at upsample 1 (those the refit keeps)."""
    captured = []

    def capture(task):
        if task.effect == "hysteresis":
            captured.append(task)
            raise _Captured
        return attribute.run_fit(task)

    monkeypatch.setattr(dg, "run_fit", capture)
    with pytest.raises(_Captured):
        dg.diagnose("sdof", case(tmp_path, "hysteresis"), tmp_path / "out", CI, fmu_dir, workers=1, progress=False)
    task = captured[0]
    starts = [task.start] + [{**task.start, **a} for a in task.alternatives]
    assert len(starts) > attribute.SCREEN_FROM
    starts = starts[::2]  # every second one (each basin keeps dozens): half the test's time
    unit = attribute.UnitScaling(list(task.start), task.bounds, task.log_scaled)
    runner = attribute.FmuRunner(task.fmu)

    def cost(start, upsample):
        p = attribute.with_derived({**task.fixed, **unit.values(unit.scaled(start))}, task.derived)
        return float(np.sum(attribute._stacked(runner, task.records, p, upsample, task.lead_periods) ** 2))

    fine = np.array([cost(s, task.upsample) for s in starts])
    coarse = np.array([cost(s, 1) for s in starts])
    runner.close()
    assert task.upsample == 4
    assert scipy.stats.spearmanr(fine, coarse)[0] > 0.99
    basins = [task.basin(unit.values(unit.scaled(s))) for s in starts]
    for b in set(basins):  # each basin's best start is among the best SCREEN_KEPT of it on the coarse grid
        members = [k for k, bk in enumerate(basins) if bk == b]
        assert min(members, key=lambda k: fine[k]) in sorted(members, key=lambda k: coarse[k])[:attribute.SCREEN_KEPT]
