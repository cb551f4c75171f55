"""Sim-to-real gap diagnosis on the withheld-hysteresis and withheld-Coulomb-friction SDOF datasets (CI
budgets; the other two effects: test_gap.py, a file of their own so that the test workers share the four
diagnoses): the withheld effect ranked first where it acts, the friction force recovered; the loop refit's starts
ranked alike at the sensor rate and upsampled; a parameter set's misfit on the diagnosis's split (misfit_at)."""
import json
import shutil

import numpy as np
import pytest
import scipy.stats

from gap_cases import CI, case, diagnosed, found_where_it_acts, strength_recovered
from pyfit.gap import attribute, store
from pyfit.gap.result import Diagnosis
from pyfit.gap import diagnose as dg


@pytest.fixture(scope="module")
def data_root(tmp_path_factory):
    return tmp_path_factory.mktemp("gap_loop_friction")


@pytest.mark.parametrize("effect", ["hysteresis", "coulomb_friction"])
def test_withheld_effect_is_found_where_it_acts_and_removes_the_gap(data_root, fmu_dir, effect, measured):
    found_where_it_acts(data_root, fmu_dir, effect, measured)


def test_chosen_effect_recovers_the_withheld_friction_force(data_root, fmu_dir, measured):
    strength_recovered(data_root, fmu_dir, "coulomb_friction", "F_c", measured)


def test_a_parameter_set_s_misfit_on_the_diagnosis_split(data_root, fmu_dir, measured):
    """misfit_at on the withheld-friction dataset: at the calibrated nominal's values it gives the report's
    held-out gap (the same split and simulation); at the truth (the CasADi reference's parameters, the nominal's
    calibrated others kept) it stays within the noise floor's reach on both the held-out and the calibration
    files (each against the floor of its own files: a lower level's is higher), far below the nominal's gap."""
    out = diagnosed(data_root, fmu_dir, "coulomb_friction")
    rep = Diagnosis.read(out / "report.json")
    data = case(data_root, "coulomb_friction")
    at_nominal = dg.misfit_at("sdof", data, rep.nominal.params, CI, fmu_dir)
    assert at_nominal.held_out == pytest.approx(rep.gap.overall, rel=1e-9)
    truth = json.loads((data / "truth.json").read_text())["params"]
    at_truth = dg.misfit_at("sdof", data, {**rep.nominal.params, **truth}, CI, fmu_dir)
    floor = rep.gap.noise_floor
    measured("truth's held-out NRMSE over the noise floor (withheld friction, FMU at the CasADi truth)",
             at_truth.held_out / floor, 1.5)
    cal_floor = np.sqrt(np.mean([d.noise_floor ** 2 for d in rep.gap.by_level if not d.held_out]))
    assert at_truth.calibration < 1.5 * cal_floor and at_nominal.held_out > 5 * at_truth.held_out


class _Captured(Exception):
    pass


def test_the_loop_starts_rank_alike_at_the_sensor_rate_and_upsampled(data_root, fmu_dir, tmp_path, monkeypatch):
    """The SDOF hysteresis refit's starts on the withheld-hysteresis dataset (CasADi reference; the diagnosis
    above resumed with that refit undone, so that its task is built as a diagnosis builds it): their
    calibration misfits at upsample 1 and at the refit's upsample (4) have a rank correlation above 0.99, and
    each basin's best start at upsample 4 is among its best SCREEN_KEPT at upsample 1 (those the refit keeps)."""
    captured = []

    def capture(task):
        if task.effect == "hysteresis":
            captured.append(task)
            raise _Captured
        return attribute.run_fit(task)

    out = tmp_path / "out"
    shutil.copytree(diagnosed(data_root, fmu_dir, "hysteresis"), out)
    (out / "fits" / "hysteresis.json").unlink()
    monkeypatch.setattr(store, "run_fit", capture)
    with pytest.raises(_Captured):
        dg.diagnose("sdof", case(data_root, "hysteresis"), out, CI, fmu_dir, workers=1, progress=False)
    task = captured[0]
    starts = [task.start] + [{**task.start, **a} for a in task.alternatives]
    assert len(starts) > attribute.SCREEN_FROM
    starts = starts[::3]  # every third one (each basin keeps dozens): a third of the test's time
    unit = attribute.UnitScaling(list(task.start), task.bounds, task.log_scaled)
    runner = attribute.FmuRunner(task.fmu)

    def cost(start, upsample):
        p = attribute.with_derived({**task.fixed, **unit.values(unit.scaled(start))}, task.derived)
        return float(np.sum(attribute.stacked_residuals(runner, task.records, p, upsample, task.lead_periods) ** 2))

    fine = np.array([cost(s, task.upsample) for s in starts])
    coarse = np.array([cost(s, 1) for s in starts])
    runner.close()
    assert task.upsample == 4
    assert scipy.stats.spearmanr(fine, coarse)[0] > 0.99
    basins = [task.basin(unit.values(unit.scaled(s))) for s in starts]
    for b in set(basins):  # each basin's best start is among the best SCREEN_KEPT of it on the coarse grid
        members = [k for k, bk in enumerate(basins) if bk == b]
        assert min(members, key=lambda k: fine[k]) in sorted(members, key=lambda k: coarse[k])[:attribute.SCREEN_KEPT]
