"""The next test a report proposes (pyfit.gap.proposal, `stockbridge plan-test`): which reports get one, the tests
tried, the drive file; and on the bundled shaker test with its runner-up held close, the separation the proposal
predicts for its best test against the one measured when the truth (the CasADi reference, another solver) runs it."""
import dataclasses
import json

import numpy as np
import pytest

from pyfit.gap import proposal
from pyfit.gap.result import Detection, Diagnosis, Gap, ModelFit, NominalFit, Verdict

GAP = Gap(overall=0.02, noise_floor=0.01, noise_floor_scaled=0.01, noise_floor_method=(), significant=True,
          worst_band_hz=(20.0, 30.0), by_band=(), by_level=())


def _fit(name, shrink):
    return ModelFit(name, (name,), shrink, 0.02, 0.011, shrink, {}, 1, 0.01, 100, True)


def _report(verdict, close=False, detection=None):
    gap = dataclasses.replace(GAP, detection=detection, significant=verdict is not Verdict.NO_GAP)
    return Diagnosis("sdof", "SDOFBoucWen", "data", verdict, ("cubic_stiffness",) if verdict is Verdict.EXPLAINED
                     else (), 0.03, gap, (_fit("cubic_stiffness", 99.0), _fit("hysteresis", 90.0)), (),
                     NominalFit({}, 0.1, 60), ("a",), ("b",), runner_up_close=close)


def test_only_a_report_that_is_not_decisive_gets_a_test():
    assert proposal.leaders(_report(Verdict.EXPLAINED)) is None
    assert proposal.leaders(_report(Verdict.EXPLAINED, close=True)) == ("cubic_stiffness", "hysteresis")
    assert proposal.leaders(_report(Verdict.NOT_EXPLAINED)) == ("cubic_stiffness", "hysteresis")
    near = Detection("quadratic_damping", 0.0098, 0.01, False, 0.03, 0.05, False)  # cut 0.03 of the 0.05 needed
    far = dataclasses.replace(near, cut=0.01)
    assert proposal.leaders(_report(Verdict.NO_GAP, detection=near)) == ("quadratic_damping", "nominal")
    assert proposal.leaders(_report(Verdict.NO_GAP, detection=far)) is None


def test_the_tests_tried_cover_every_band_and_level_and_last_as_planned():
    from pyfit.gap.simulate import Record

    t = np.arange(1000) / 500.0
    records = [Record(f"l{a}", "", a, 500.0, {"u": a * np.sin(2 * np.pi * 10 * t)}, {"y": 0 * t}, 0)
               for a in (10.0, 50.0)]
    bands = [(5.0, 10.0), (10.0, 20.0), (20.0, 40.0)]
    plans = proposal.candidate_tests(records, bands, clamp=False)
    # half the lowest, the highest, 1.5 x it: each read as the input's peak (a 10 Hz sine sampled at 500 Hz has its
    # crest at most half a sample from a sample: cos(2 pi 10 / 1000) = 0.998 of the amplitude)
    assert sorted({round(p.level, 9) for p in plans}) == pytest.approx([5.0, 50.0, 75.0], rel=2e-3)
    assert len(plans) == len(proposal.LEVEL_FACTORS) * (len(bands) + 1)
    step = next(p for p in plans if p.kind == "stepped sine" and p.band_hz == (5.0, 10.0))
    assert step.dwell_s == pytest.approx(proposal.DWELL_PERIODS / 5.0) and step.duration_s == pytest.approx(20.0)
    rec = proposal.record_of_test(step, 500.0, False, ("y",))
    assert len(rec.inputs["u"]) == 10000 and np.max(np.abs(rec.inputs["u"])) == pytest.approx(step.level, rel=1e-3)


@pytest.mark.slow
def test_the_predicted_separation_is_the_one_the_truth_shows(tmp_path, fmu_dir, measured):
    """The bundled shaker test (a hardening spring withheld) diagnosed with its runner-up held close: the proposal's
    best test, run by the truth (CasADi reference, CVODES, no noise), misfits the runner-up's prediction by what
    the proposal predicted the two models differ by, within 30 % (the named model predicts the truth there)."""
    from pyfit.catalog import copy_dataset
    from pyfit.gap.diagnose import DiagnoseConfig, diagnose
    from pyfit.reference.synthetic import SyntheticSpec, simulate_truth
    from pyfit.runtime.fmu import FmuRunner
    from pyfit.gap import simulate as sim

    data = copy_dataset("lab_sweeps", tmp_path / "data")
    d = diagnose("sdof", data, tmp_path / "out", DiagnoseConfig(close_points=1000.0), fmu_dir, workers=2,
                 progress=False)
    assert d.chosen == ("cubic_stiffness",) and d.runner_up_close
    pr, (_, records, system) = proposal.plan_test(tmp_path / "out", DiagnoseConfig(close_points=1000.0), fmu_dir)
    proposal.write_plan(pr, d, records, system, tmp_path / "plan")
    assert (tmp_path / "plan" / "next_test.toml").is_file()
    assert pr.between == (d.ranking[0].effect, d.ranking[1].effect)
    fs, outputs = records[0].fs, tuple(records[0].outputs)  # the accelerometer's "a"
    rec = proposal.record_of_test(pr.test, fs, False, outputs)
    truth = {"m": 2.0, "c": 10.0, "k": 1e5, "alpha": 0.0, "k3": 3e8}  # the dataset's README.txt
    _, exact, _ = simulate_truth(SyntheticSpec("SDOFBoucWen", pr.test.signal(False), pr.test.duration_s, fs,
                                               list(outputs), truth, rtol=1e-8, atol=1e-12))
    runner = FmuRunner(str(fmu_dir / "SDOFBoucWen.fmu"))
    runner_up, named = (sim.simulate(runner, rec, f.values, 4, 1) for f in d.ranking[:2][::-1])
    runner.close()
    noise = proposal.sensor_noise(records)
    n = rec.n
    shown = proposal.separation({k: exact[k][:n] - np.mean(exact[k][:n]) for k in outputs}, runner_up, noise)
    measured("next test on the bundled shaker test: |separation the truth shows / predicted - 1|",
             abs(shown / pr.separation - 1.0), 0.3)
    off = proposal.separation({k: exact[k][:n] - np.mean(exact[k][:n]) for k in outputs}, named, noise)
    assert off < 0.3 * pr.separation  # the named model predicts the truth there
    assert json.loads((tmp_path / "out" / "report.json").read_text())["nominal"]["values"]
