"""attribute.run_fit with many starts: they are ranked on the FMU's input grid at the sensor rate (upsample 1)
first, and only the best of each basin is scored at the refit's upsample (that the two grids order the SDOF
loop's starts alike: test_gap_loop_friction.py); the best BASINS_ON basins' probes go on with the whole budget."""
import types

import numpy as np
import pytest

from pyfit.fit.optim.result import OptimResult
from pyfit.gap import attribute


_RECORD = types.SimpleNamespace(level_value=1.0, periodic=True, outputs={"y": None}, weights={})  # one periodic record


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

    monkeypatch.setattr(attribute, "stacked_residuals", stacked)
    monkeypatch.setattr(attribute, "FmuRunner", _NoRunner)
    grid = [{"a": a, "b": b} for a in np.linspace(0.0, 1.0, 9) for b in np.linspace(0.0, 1.0, 9)]  # 81 starts
    task = attribute.FitTask("x.fmu", (_RECORD,), {}, {"a": 0.5, "b": 0.5}, {"a": (0.0, 1.0), "b": (0.0, 1.0)}, "e",
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


def test_a_slow_basin_that_probes_second_goes_on_and_wins(monkeypatch):
    """Two basins of a parameter a: below 0.5 a steep one (misfit 5|a - 0.2|) whose descent covers the way to its
    minimum at a = 0.2 only after 100 evaluations, above it a shallow one stuck at 0.3. After the probes (a third
    of the 120 evaluations) the steep basin misfits more (0.6 against 0.3); going on with both, the refit ends at
    its minimum."""

    def misfit(a):
        return 5.0 * abs(a - 0.2) if a < 0.5 else 0.3 + 0.1 * abs(a - 0.8)

    def stacked(runner, records, params, upsample, lead_periods, pool=None, of=None):
        return np.array([misfit(params["a"])])

    def descent(residuals, x0, budget, margin):  # a fixed share of the way to the basin's minimum per evaluation
        goal = 0.2 if x0[0] < 0.5 else 0.8
        x = x0 + (goal - x0) * min(1.0, budget / 100)
        return OptimResult(x, float(np.sum(residuals(x) ** 2)), budget, "budget", [], 0.0)

    monkeypatch.setattr(attribute, "stacked_residuals", stacked)
    monkeypatch.setattr(attribute, "polish", descent)
    monkeypatch.setattr(attribute, "FmuRunner", _NoRunner)
    task = attribute.FitTask("x.fmu", (_RECORD,), {}, {"a": 1.0}, {"a": (0.0, 1.0)}, "e", 1, 120, 4,
                             alternatives=({"a": 0.0},), basin=_half, continuation=False)
    fit = attribute.run_fit(task)
    assert misfit(0.0 + 0.2 * 40 / 100) == pytest.approx(0.6)  # the steep basin's probe: behind the shallow one
    assert fit.params["a"] == pytest.approx(0.2) and fit.calibration_nrmse == pytest.approx(0.0, abs=1e-12)
