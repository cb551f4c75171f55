"""Sim-to-real gap diagnosis on withheld-effect SDOF datasets (CI budgets), cubic stiffness and quadratic
damping (hysteresis and Coulomb friction: test_gap_loop_friction.py): the withheld effect ranked first, the
largest misfit around the resonance it shifts, at least 80 % of the held-out gap removed, its strength
recovered; an interrupted diagnosis resumes; a close runner-up gets a level and band to measure."""

import pytest

from gap_cases import CI, case, diagnosed, found_where_it_acts, strength_recovered
from pyfit.gap import diagnose as dg
from pyfit.gap import store
from pyfit.gap.result import Diagnosis


@pytest.fixture(scope="module")
def data_root(tmp_path_factory):
    return tmp_path_factory.mktemp("gap")


@pytest.mark.parametrize("effect", ["cubic_stiffness", "quadratic_damping"])
def test_withheld_effect_is_found_where_it_acts_and_removes_the_gap(data_root, fmu_dir, effect, measured):
    found_where_it_acts(data_root, fmu_dir, effect, measured)


@pytest.mark.parametrize("effect, strength", [("cubic_stiffness", "k3"), ("quadratic_damping", "c2")])
def test_chosen_effect_recovers_the_withheld_strength(data_root, fmu_dir, effect, strength, measured):
    strength_recovered(data_root, fmu_dir, effect, strength, measured)


def test_interrupted_diagnosis_resumes_from_finished_refits(data_root, fmu_dir, monkeypatch):
    out = diagnosed(data_root, fmu_dir, "quadratic_damping")
    before = Diagnosis.read(out / "report.json")
    (out / "fits" / "cubic_stiffness.json").unlink()  # as if killed while that refit ran
    calls = []
    real = store.run_fit
    monkeypatch.setattr(store, "run_fit", lambda task: calls.append(task.effect) or real(task))
    rep = dg.diagnose("sdof", case(data_root, "quadratic_damping"), out, CI, fmu_dir, workers=1, progress=False)
    assert calls == ["cubic_stiffness"]
    after = {r.effect: r.shrink_pct for r in rep.ranking}
    for r in before.ranking:
        if r.effect != "cubic_stiffness":
            assert after[r.effect] == pytest.approx(r.shrink_pct, abs=1e-9)


def test_a_refit_is_the_same_on_one_thread_as_on_two(data_root, sdof_system, monkeypatch):
    """A fit simulating its calibration records on two threads (one FMU instance each; every fit of a
    diagnosis on several cores may) ends at exactly the parameters and misfit it reaches on one (every run
    made afresh: the process's memory of runs keeps nothing here)."""
    from pyfit.gap.attribute import nominal_task
    from pyfit.runtime import drive
    from pyfit.runtime.memo import BoundedMemo

    monkeypatch.setattr(drive, "RESPONSE_MEMO", BoundedMemo(max_bytes=0))

    runner, system = sdof_system
    fmu = runner.path
    cal = dg._load(case(data_root, "cubic_stiffness"), system, CI, runner).cal
    assert len(cal) >= 2  # two records to simulate at once
    one, two = (dg.run_fit(nominal_task(system, fmu, cal, 12, system.upsample, threads=n)) for n in (1, 2))
    assert one.params == two.params and one.calibration_nrmse == two.calibration_nrmse
    assert one.evaluations == two.evaluations > 1


def test_close_runner_up_gets_a_level_and_band_to_measure(data_root, fmu_dir):
    # reuse the stored refits of the quadratic-damping case; call every runner-up close (close_points 100)
    out = diagnosed(data_root, fmu_dir, "quadratic_damping")
    cfg = dg.DiagnoseConfig(nominal_budget=30, refit_budget=60, close_points=100.0)
    rep = dg.diagnose("sdof", case(data_root, "quadratic_damping"), out, cfg, fmu_dir, workers=1, progress=False)
    sep = rep.separation
    assert rep.runner_up_close and sep.between == tuple(r.effect for r in rep.ranking[:2])
    # the candidates were simulated at the three measured levels and beyond them (x0.3, x2)
    assert len(sep.levels) == 5
    best = sep.measure_next
    assert best["difference_nrmse"] == max(d["difference_nrmse"] for d in sep.levels) > 0
    assert best["band_hz"][0] < best["band_hz"][1]
    assert "score close" in (out / "report.md").read_text()
    # not decisive: the report names the next test, as `stockbridge plan-test` proposes it from the report
    from pyfit.gap.proposal import plan_test

    proposed, _ = plan_test(out, cfg, fmu_dir)
    nt = rep.next_test
    assert nt.between == sep.between == proposed.between and nt.test == proposed.test.sentence()
    assert nt.separation == pytest.approx(proposed.separation, rel=1e-9) and nt.separation > 1.0
    assert f"**Next test: {nt.test}.**" in (out / "report.md").read_text()


def test_a_pinned_refit_holds_the_given_values_and_tries_each_remaining_start_once():
    """attribute.pinned: the held parameters leave the fitted set (start, bounds, log scaling, every start)
    for the fixed ones; starts that differed only in them are tried once; it descends from the best of them
    only (the joint refit it seeds probes)."""
    from pyfit.gap.attribute import FitTask, pinned

    task = FitTask("x.fmu", (), {"m": 2.0}, {"k": 1e5, "k3": 0.0, "c2": 0.0},
                   {"k": (5e4, 2e5), "k3": (-1e9, 1e9), "c2": (1e-3, 10.0)}, "cubic_stiffness + quadratic_damping",
                   2, 120, 1, alternatives=({"k3": 1e8}, {"k3": -1e8}, {"k3": 1e8, "c2": 2.0}),
                   log_scaled=("c2", "k3"), probes=3)
    held = pinned(task, {"k3": 5e8}, 60)
    assert held.probes == 1 and task.probes == 3
    assert held.fixed == {"m": 2.0, "k3": 5e8}
    assert held.start == {"k": 1e5, "c2": 0.0} and set(held.bounds) == {"k", "c2"}
    assert held.alternatives == ({}, {"c2": 2.0}) and held.log_scaled == ("c2",) and held.budget == 60


def test_a_pair_with_a_loop_descends_from_each_loop_basin_and_so_does_the_loop_beside_a_held_partner():
    """effect.combine carries the loop's basins (a weak loop beside a strong spring lies in another basin than
    the loop alone); attribute.pinned keeps them while the loop's shape is fitted (the loop beside a held spring)
    and drops them once it is held (the spring beside the held loop has no loop basins left)."""
    from pyfit.gap.attribute import FitTask, pinned
    from pyfit.gap.effect import Scale, combine
    from pyfit.gap.effects import candidates, sdof_loop_basin

    pair = combine([candidates("sdof")["cubic_stiffness"], candidates("sdof")["hysteresis"]])
    assert pair.basin is sdof_loop_basin and combine([candidates("sdof")["cubic_stiffness"],
                                                      candidates("sdof")["quadratic_damping"]]).basin is None
    shape = {"F_t": 30.0, "branch": -0.5, "nu": 2.0}
    basin = pair.basin(Scale(1e-3, 0.2, 1e5))
    task = FitTask("x.fmu", (), {"m": 2.0}, {"k": 1e5, "alpha": 1e4, "k3": 0.0, **shape},
                   {n: (-10.0, 10.0) for n in ("k", "alpha", "k3", *shape)}, pair.name, 2, 120, 1, basin=basin)
    assert pinned(task, {"k3": 1e8}, 60).basin is basin
    assert pinned(task, {"alpha": 1e4, **shape}, 60).basin is None


def test_a_diagnosis_runs_its_linear_algebra_on_one_blas_thread(tmp_path, monkeypatch):
    """A multi-threaded BLAS rounds by its thread count and a multistart least squares amplifies that into another
    path: a diagnosis holds every BLAS library on one thread (as a Dask worker starts), whatever the caller set."""
    import threadpoolctl

    seen = []

    def probe(*args, **kwargs):  # the first step of a diagnosis after the FMU is loaded: record and stop there
        seen.extend(i["num_threads"] for i in threadpoolctl.threadpool_info() if i["user_api"] == "blas")
        raise RuntimeError("stopped by the test")

    monkeypatch.setattr(dg, "make_system", probe)
    monkeypatch.setattr(dg, "ensure_fmu", lambda name, where: "unused.fmu")
    monkeypatch.setattr(dg, "FmuRunner", lambda fmu: None)
    monkeypatch.setattr(dg, "fmu_defaults", lambda runner: {})
    with threadpoolctl.threadpool_limits(limits=2, user_api="blas"):
        with pytest.raises(RuntimeError, match="stopped by the test"):
            dg.diagnose("sdof", tmp_path, tmp_path / "out", progress=False)
        after = [i["num_threads"] for i in threadpoolctl.threadpool_info() if i["user_api"] == "blas"]
    assert seen and set(seen) == {1}
    assert set(after) == {2}  # the caller's setting is back once the diagnosis returns
    # and so does each fit a diagnosis runs in a worker process, which starts with the machine's default
    monkeypatch.setattr(store, "run_fit", probe)
    seen.clear()
    with threadpoolctl.threadpool_limits(limits=2, user_api="blas"):
        with pytest.raises(RuntimeError, match="stopped by the test"):
            store.fit_and_store((None, tmp_path / "fit.json", "key", "a stage"))
    assert seen and set(seen) == {1}
