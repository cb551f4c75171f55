"""Candidates a user declares without touching pyfit (pyfit.gap.user_candidates): the file's checks, and the
docs' example — a Maxwell element (frequency-dependent stiffness and loss) built from the user's own Modelica
package beside the library — named on data that has it. The data is the analytic steady state of the SDOF
with a Maxwell element under a random-odd multisine (its FRF, computed here), written as a lab writes files."""
import pathlib

import numpy as np
import pytest

from pyfit.analysis.excitation import multisine
from pyfit.gap import user_candidates
from pyfit.gap.effect import Scale
from pyfit.io.data import write_measurement

ROOT = pathlib.Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "maxwell_candidate"


def _write(tmp_path, text: str) -> pathlib.Path:
    p = tmp_path / "cands.toml"
    p.write_text(text)
    return p


GOOD = """
[[candidate]]
name = "backlash"
[[candidate.parameter]]
name = "gap_width"
lower = 0
start = "0.5 * sigma_y"
upper = "4 * sigma_y"
"""


def test_a_declared_candidate_has_its_bounds_and_start_from_the_data_scale(tmp_path):
    c = user_candidates.load(_write(tmp_path, GOOD))
    (p,) = c.effects["backlash"].params
    assert p.range(Scale(2e-3, 0.1, 1e5, {})) == (0.0, 1e-3, 8e-3)
    assert c.fmu is None and not c.effects["backlash"].linear  # a candidate tells a gap below the noise by default
    declared = GOOD.replace('name = "backlash"', 'name = "backlash"\nlinear = true')
    marked = user_candidates.load(_write(tmp_path, declared))
    assert marked.effects["backlash"].linear


def test_a_declared_friction_ranges_up_to_the_force_of_a_stuck_joint(tmp_path):
    text = GOOD.replace('upper = "4 * sigma_y"', 'upper = "2 * stuck_force + k * sigma_y"')
    (p,) = user_candidates.load(_write(tmp_path, text)).effects["backlash"].params
    assert p.range(Scale(2e-3, 0.1, 1e5, {}, 3.0)) == pytest.approx((0.0, 1e-3, 6.0 + 200.0), rel=1e-15)


@pytest.mark.parametrize("change, where", [
    (("start = \"0.5 * sigma_y\"", "start = \"__import__('os')\""), "candidate[0].parameter[0].start"),
    (("start = \"0.5 * sigma_y\"", "start = \"0.5 * omega\""), "candidate[0].parameter[0].start"),
    (("lower = 0", "lower = true"), "candidate[0].parameter[0].lower"),
    (("name = \"gap_width\"", "name = \"gap_width\"\nshape = true"), "candidate[0].parameter"),
    (("[[candidate]]", "fmu = \"nowhere.fmu\"\n[[candidate]]"), "fmu"),
    (("name = \"backlash\"", "name = \"backlash\"\ncolour = 1"), "candidate[0].colour"),
    (("name = \"backlash\"", "name = \"backlash\"\nlinear = 1"), "candidate[0].linear"),
])
def test_a_bad_declaration_is_refused_naming_the_file_and_key(tmp_path, change, where):
    path = _write(tmp_path, GOOD.replace(*change))
    with pytest.raises(user_candidates.CandidateError) as exc:
        user_candidates.load(path)
    assert str(path) in str(exc.value) and where in str(exc.value)


def _maxwell_dataset(folder: pathlib.Path, k_m: float, tau: float, seed: int = 0) -> pathlib.Path:
    """Three levels (RMS 10, 25, 50 N) of the steady-state SDOF (m = 2 kg, c = 10 N·s/m, k = 1e5 N/m) with a
    Maxwell element (k_m [N/m] in series with a dashpot k_m·tau) to ground: y = irfft(U · H), H(ω) =
    1 / (k − m ω² + i ω c + k_m i ω tau / (1 + i ω tau)); 3 periods of 2048 samples at 500 Hz, 5e-6 m noise."""
    rng = np.random.default_rng(seed)
    fs, n = 500.0, 2048
    w = 2 * np.pi * np.fft.rfftfreq(n, 1 / fs)
    h = 1.0 / (1e5 - 2.0 * w ** 2 + 1j * w * 10.0 + k_m * 1j * w * tau / (1 + 1j * w * tau))
    for i, rms in enumerate((10.0, 25.0, 50.0)):
        u = multisine(n, fs, 5.0, 80.0, rms, seed=7, odd=True)
        y = np.fft.irfft(np.fft.rfft(u) * h, n)
        u3, y3 = np.tile(u, 3), np.tile(y, 3) + rng.normal(0.0, 5e-6, 3 * n)
        write_measurement(folder / f"level{i + 1}.csv", "SDOFBoucWen", np.arange(3 * n) / fs,
                          {"force": (u3, "N", "u")}, {"y_meas": (y3, "m", "y")}, level=f"RMS {rms:g} N",
                          level_value=rms, excitation={"kind": "multisine", "samples_per_period": n, "periods": 3})
    return folder


@pytest.mark.slow
def test_the_docs_maxwell_candidate_is_built_declared_and_named(tmp_path, fmu_dir, measured):
    from pyfit.build import LIBRARY, build_all
    from pyfit.gap.diagnose import diagnose

    build_all(tmp_path / "fmus", ["MyDampers.SDOFMaxwell"], [LIBRARY, EXAMPLE])
    declared = _write(tmp_path, (EXAMPLE / "maxwell.toml").read_text())  # its fmu is fmus/ beside it
    data = _maxwell_dataset(tmp_path / "data", k_m=3e4, tau=1 / (2 * np.pi * 35.0))
    rep = diagnose("sdof", data, tmp_path / "out", fmu_dir=fmu_dir, workers=2, progress=False, candidates=declared)
    assert rep.chosen_name == "maxwell_damping", (rep.sentence, rep.ranking[:2])
    best = rep.ranking[0]
    measured("a user-declared candidate (Maxwell element) on data that has it: held-out shrink [%]",
             best.shrink_pct, 90.0, at_least=True)
    measured("the same: fitted k_m relative to the truth", abs(best.params["k_m"] / 3e4 - 1), 0.05)
