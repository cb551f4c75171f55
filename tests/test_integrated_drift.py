"""A clamp read by an accelerometer alone: the displacement integrated from it drifts below the excited band (the
sensor's offset and low-frequency noise, integrated twice), the measured cable-end displacements do not. The
diagnosis compares the model's outputs and the measured ones above half the band's lower edge
(simulate.COMPARED_FROM), and not over the first seconds, where the drift's unknown start sets the model ringing:
the truth then fits the held-out files within the criterion a model must meet to explain them, under every
excitation of the generator, where compared down to 0 Hz the drift it is driven by misfits them many times over. Without a drift,
the same records are compared in full."""
import json

import numpy as np
import pytest

from pyfit.gap import datasets, selection, simulate
from pyfit.gap.config import DiagnoseConfig
from pyfit.gap.diagnose import misfit_at, prepare
from pyfit.gap.localise import noise_estimates
from pyfit.io.data import read_measurement

DRIFT_SHARE = 0.02  # the accelerometer's low-frequency noise (below 1 Hz), RMS over the clamp acceleration's RMS


def _with_accelerometer_drift(folder, rng):
    """Every file's clamp acceleration column with an accelerometer's offset and low-frequency noise added."""
    for csv in sorted(folder.glob("level*.csv")):
        m = read_measurement(csv)
        a = m.values["a_base_meas"]
        walk = np.cumsum(rng.normal(size=a.size))
        slow = np.convolve(walk - walk.mean(), np.ones(int(m.sample_rate_hz)), "same")  # under ~1 Hz
        drift = 0.01 * np.std(a) + DRIFT_SHARE * np.std(a) * slow / np.std(slow)
        lines = csv.read_text().splitlines()
        header = lines[0].split(",")
        col = header.index("a_base_meas")
        rows = [line.split(",") for line in lines[1:]]
        for row, d in zip(rows, drift):
            row[col] = f"{float(row[col]) + d:.10g}"
        csv.write_text("\n".join([lines[0]] + [",".join(r) for r in rows]) + "\n")


@pytest.mark.parametrize("excitation", ["stepped_sine", pytest.param("sweep", marks=pytest.mark.slow),
                                        pytest.param("noise", marks=pytest.mark.slow)])
def test_the_truth_fits_records_whose_clamp_was_integrated_from_an_accelerometer(tmp_path, fmu_dir, excitation,
                                                                               measured, monkeypatch):
    rng = np.random.default_rng(41)
    data = datasets.write_dataset(tmp_path / "data", datasets.DAMPER, "none", seed=5,
                                  style=datasets.LabStyle(excitation, ("x1", "x2"), "a", record_s=8.0))
    clean = prepare("damper", data, DiagnoseConfig(), fmu_dir)
    assert all(r.compared_from_hz == 0 and r.first == 0 for r in clean.data.records)  # no drift: all of it compared
    clean.runner.close()
    _with_accelerometer_drift(data, rng)
    truth = json.loads((data / "truth.json").read_text())["params"]
    p = prepare("damper", data, DiagnoseConfig(), fmu_dir)
    floor = float(np.sqrt(np.mean([noise_estimates(p.data.records)[r.name][0] ** 2 for r in p.data.held])))
    # x_base integrated from a drifting sensor: compared above a frequency, and not over the start
    assert all(r.compared_from_hz > 0 and r.first > 0 for r in p.data.records)
    p.runner.close()
    held = misfit_at("damper", data, truth, fmu_dir=fmu_dir).held_out
    cfg = DiagnoseConfig()
    criterion = selection.explained_below(floor, cfg.explain_factor, cfg.explain_margin)
    measured(f"damper, clamp integrated from an accelerometer with drift, {excitation}: the truth's held-out NRMSE "
             "over the noise floor (at most the criterion for 'explained')", held / floor, criterion / floor)
    monkeypatch.setattr(simulate, "COMPARED_FROM", 0.0)  # compared down to 0 Hz: the drift shows
    assert misfit_at("damper", data, truth, fmu_dir=fmu_dir).held_out > 10 * criterion
