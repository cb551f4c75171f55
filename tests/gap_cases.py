"""Shared by the SDOF gap-diagnosis test files: the withheld-effect datasets, the CI budgets and the checks
each withheld effect's diagnosis must pass."""
import json

import numpy as np

from pyfit.gap import datasets
from pyfit.gap.result import Diagnosis
from pyfit.gap import diagnose as dg

# CI budgets: fewer evaluations per fit, and the forward selection from the best single effect only with three
# partners (the default search, two starts and every partner, runs in the slow tier and the campaign)
CI = dg.DiagnoseConfig(nominal_budget=30, refit_budget=60, beam=1, partners=3)


def case(root, effect, seed=0):
    """The dataset of that withheld effect ('none': a null case), written once per test module."""
    path = root / f"{effect}_seed{seed}"
    if not path.is_dir():
        datasets.write_dataset(path, datasets.SDOF, effect, seed=seed, periods=2)
    return path


F0 = np.sqrt(1e5 / 2.0) / (2 * np.pi)  # 35.6 Hz, the truth's linear resonance


def diagnosed(root, fmu_dir, effect):
    """The output folder of a finished diagnosis of that case (run here unless a test above ran it: the
    stored fits make the second call a resume)."""
    out = root / f"out_{effect}"
    if not (out / "report.json").is_file():
        dg.diagnose("sdof", case(root, effect), out, CI, fmu_dir, workers=2, progress=False)
    return out


def found_where_it_acts(root, fmu_dir, effect, measured):
    """The withheld effect (changing the middle level's output RMS by 5-30 %) is chosen and ranked first, removes
    at least 80 % of the held-out gap, and the worst band holds the resonance it shifts."""
    data = case(root, effect)
    change = json.loads((data / "truth.json").read_text())["rms_change"]["25"]["rms"]
    assert 0.05 <= abs(change) <= 0.30
    rep = dg.diagnose("sdof", data, root / f"out_{effect}", CI, fmu_dir, workers=2, progress=False)
    assert rep.chosen_name == effect and rep.ranking[0].effect == effect
    measured(f"SDOF gap diagnosis, {effect} withheld (CI budgets): held-out shrink of the chosen effect [%]",
             rep.ranking[0].shrink_pct, 80.0, at_least=True)
    lo, hi = rep.gap.worst_band_hz
    assert lo <= F0 <= hi
    assert rep.gap.overall > 5 * rep.gap.noise_floor
    assert rep.clipped_channels == {}  # the noisy records within range: no channel taken for a clipped one
    assert (root / f"out_{effect}" / "report.md").is_file()


def strength_recovered(root, fmu_dir, effect, strength, measured):
    """The chosen effect removes at least 95 % of the held-out gap, the report states no confidence (no campaign
    was run with the CI budgets: a calibration is of the settings it was made with), and the refit's strength is
    within 2 % of the truth's
    (k3 = 3e8 N/m^3, F_c = 1 N, c2 = 10 N·s²/m²; the friction's smoothing velocity v_s is fitted with F_c,
    log-scaled, but barely shapes these displacement records)."""
    truth = json.loads((case(root, effect) / "truth.json").read_text())["params"][strength]
    out = diagnosed(root, fmu_dir, effect)
    rep = Diagnosis.read(out / "report.json")
    best = rep.ranking[0]
    assert best.effect == effect and best.shrink_pct >= 95.0  # measured 100 % on each
    assert rep.confidence is None and "Confidence" not in (out / "report.md").read_text()
    measured(f"SDOF gap diagnosis, {effect} withheld (CI budgets): |fitted {strength} / truth − 1|",
             abs(best.params[strength] / truth - 1), 0.02)
