"""Sim-to-real gap diagnosis on withheld-effect SDOF datasets (CI budgets): the withheld effect ranked
first, the largest misfit around the resonance it shifts, at least 80 % of the held-out gap removed; no
false alarm on null datasets; clear errors on bad input; an interrupted diagnosis resumes."""
import json
import shutil

import numpy as np
import pytest

from pyfit.gap import datasets
from pyfit.gap import diagnose as dg

CI = dg.DiagnoseConfig(nominal_budget=30, refit_budget=60)
F0 = np.sqrt(1e5 / 2.0) / (2 * np.pi)  # 35.6 Hz, the truth's linear resonance


@pytest.fixture(scope="module")
def data_root(tmp_path_factory):
    return tmp_path_factory.mktemp("gap")


def _case(root, effect, seed=0):
    path = root / f"{effect}_seed{seed}"
    if not path.is_dir():
        datasets.write_dataset(path, datasets.SDOF, effect, seed=seed, periods=2)
    return path


def _diagnosed(root, fmu_dir, effect):
    """The output folder of a finished diagnosis of that case (run here unless a test above ran it: the
    stored fits make the second call a resume)."""
    out = root / f"out_{effect}"
    if not (out / "report.json").is_file():
        dg.diagnose("sdof", _case(root, effect), out, CI, fmu_dir, workers=2, progress=False)
    return out


@pytest.mark.parametrize("effect", ["hysteresis", "cubic_stiffness", "coulomb_friction", "quadratic_damping"])
def test_withheld_effect_is_found_where_it_acts_and_removes_the_gap(data_root, fmu_dir, effect, measured):
    data = _case(data_root, effect)
    change = json.loads((data / "truth.json").read_text())["rms_change"]["25"]["rms"]
    assert 0.05 <= abs(change) <= 0.30  # the effect changes the middle level's output RMS by 5-30 %
    rep = dg.diagnose("sdof", data, data_root / f"out_{effect}", CI, fmu_dir, workers=2, progress=False)
    assert rep["chosen_effect"] == effect and rep["ranking"][0]["effect"] == effect
    measured(f"SDOF gap diagnosis, {effect} withheld (CI budgets): held-out shrink of the chosen effect [%]",
             rep["ranking"][0]["shrink_pct"], 80.0, at_least=True)
    lo, hi = rep["gap"]["worst_band_hz"]
    assert lo <= F0 <= hi
    assert rep["gap"]["overall"] > 5 * rep["gap"]["noise_floor"]
    assert (data_root / f"out_{effect}" / "report.md").is_file()


@pytest.mark.parametrize("effect, strength", [("cubic_stiffness", "k3"), ("coulomb_friction", "F_c"),
                                              ("quadratic_damping", "c2")])
def test_chosen_effect_recovers_the_withheld_strength(data_root, fmu_dir, effect, strength, measured):
    # the refit's strength against the truth's (k3 = 3e8 N/m^3, F_c = 1 N, c2 = 10 N·s²/m²); the friction's
    # smoothing velocity v_s is fitted with F_c (log-scaled) but barely shapes these displacement records
    truth = json.loads((_case(data_root, effect) / "truth.json").read_text())["params"][strength]
    best = json.loads((_diagnosed(data_root, fmu_dir, effect) / "report.json").read_text())["ranking"][0]
    assert best["effect"] == effect
    measured(f"SDOF gap diagnosis, {effect} withheld (CI budgets): |fitted {strength} / truth − 1|",
             abs(best["params"][strength] / truth - 1), 0.02)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_null_dataset_gives_no_false_alarm(data_root, fmu_dir, seed, measured):
    rep = dg.diagnose("sdof", _case(data_root, "none", seed), data_root / f"out_none{seed}", CI, fmu_dir,
                      workers=2, progress=False)
    assert rep["verdict"] == "no significant gap" and rep["chosen_effect"] is None
    # the nominal fit sits on the noise floor the data give (5e-6 m noise, about 0.4 % of the output RMS)
    measured(f"SDOF gap diagnosis, null dataset seed {seed} ('no significant gap'): |held-out gap / noise floor − 1|",
             abs(rep["gap"]["overall"] / rep["gap"]["noise_floor"] - 1), 0.1)


def test_interrupted_diagnosis_resumes_from_finished_refits(data_root, fmu_dir, monkeypatch):
    out = _diagnosed(data_root, fmu_dir, "quadratic_damping")
    before = json.loads((out / "report.json").read_text())
    (out / "fits" / "cubic_stiffness.json").unlink()  # as if killed while that refit ran
    calls = []
    real = dg.run_fit
    monkeypatch.setattr(dg, "run_fit", lambda task: calls.append(task.effect) or real(task))
    rep = dg.diagnose("sdof", _case(data_root, "quadratic_damping"), out, CI, fmu_dir, workers=1, progress=False)
    assert calls == ["cubic_stiffness"]
    after = {r["effect"]: r["shrink_pct"] for r in rep["ranking"]}
    for r in before["ranking"]:
        if r["effect"] != "cubic_stiffness":
            assert after[r["effect"]] == pytest.approx(r["shrink_pct"], abs=1e-9)


def test_bad_input_gives_one_clear_error(data_root, tmp_path, fmu_dir):
    src = _case(data_root, "none", 0)
    one = tmp_path / "one"
    one.mkdir()
    for ext in ("csv", "toml"):
        shutil.copy(src / f"level1_10N.{ext}", one / f"level1_10N.{ext}")
    with pytest.raises(dg.DiagnoseError, match="at least two files"):
        dg.diagnose("sdof", one, tmp_path / "o1", CI, fmu_dir)
    shutil.copy(src / "level2_25N.csv", one / "level2_25N.csv")  # no sidecar
    with pytest.raises(dg.DiagnoseError, match=r"level2_25N\.toml"):
        dg.diagnose("sdof", one, tmp_path / "o2", CI, fmu_dir)
    side = (src / "level2_25N.toml").read_text()
    (one / "level2_25N.toml").write_text(side.replace("sample_rate_hz = 500", "sample_rate_hz = 250"))
    csv = np.loadtxt(src / "level2_25N.csv", delimiter=",", skiprows=1)
    csv[:, 0] *= 2.0
    np.savetxt(one / "level2_25N.csv", csv, delimiter=",", header="t,u_meas,y_meas", comments="", fmt="%.15g")
    with pytest.raises(dg.DiagnoseError, match="sample_rate_hz = 250 but level1_10N.csv has 500"):
        dg.diagnose("sdof", one, tmp_path / "o3", CI, fmu_dir)
    with pytest.raises(dg.DiagnoseError, match="'friction' unknown for sdof; allowed: hysteresis"):
        dg.diagnose("sdof", src, tmp_path / "o4", dg.DiagnoseConfig(effects=["friction"]), fmu_dir)
    with pytest.raises(ValueError, match="--model .beam. unknown; allowed: sdof, damper"):
        dg.diagnose("beam", src, tmp_path / "o5", CI, fmu_dir)
    cfg = tmp_path / "d.toml"
    cfg.write_text("[diagnose]\nrefit_budget = 10\nbudget = 3\n")
    with pytest.raises(dg.DiagnoseError, match=r"d\.toml: \[diagnose\.budget\] unknown key; allowed: bands_hz"):
        dg.load_config(cfg)
    cfg.write_text("[diagnose]\nrefit_budget = 'many'\n")
    with pytest.raises(dg.DiagnoseError, match=r"\[diagnose\.refit_budget\] must be a whole number, not 'many'"):
        dg.load_config(cfg)


def test_close_runner_up_gets_a_level_and_band_to_measure(data_root, fmu_dir):
    # reuse the stored refits of the quadratic-damping case; call every runner-up close (close_points 100)
    out = _diagnosed(data_root, fmu_dir, "quadratic_damping")
    cfg = dg.DiagnoseConfig(nominal_budget=30, refit_budget=60, close_points=100.0)
    rep = dg.diagnose("sdof", _case(data_root, "quadratic_damping"), out, cfg, fmu_dir, workers=1, progress=False)
    sep = rep["separation"]
    assert rep["runner_up_close"] and sep["between"] == [r["effect"] for r in rep["ranking"][:2]]
    # the candidates were simulated at the three measured levels and beyond them (x0.3, x2)
    assert len(sep["levels"]) == 5
    best = sep["measure_next"]
    assert best["difference_nrmse"] == max(d["difference_nrmse"] for d in sep["levels"]) > 0
    assert best["band_hz"][0] < best["band_hz"][1]
    assert "score close" in (out / "report.md").read_text()


def test_a_skew_between_the_channels_is_named_sensor_delay(data_root, fmu_dir, measured):
    """The input channel 1.3 ms ahead of the output (unsynchronised DAQ modules): named, and the delay found."""
    rep = dg.diagnose("sdof", _case(data_root, "sensor_delay"), data_root / "out_sensor_delay", CI, fmu_dir,
                      workers=2, progress=False)
    assert rep["chosen_effect"] == "sensor_delay", rep["ranking"][:2]
    measured("SDOF gap diagnosis, a 1.3 ms skew between input and output channels: |fitted delay − 1.3 ms| [ms]",
             abs(rep["ranking"][0]["params"]["sensor_delay"] - 1.3e-3) * 1e3, 0.02)
