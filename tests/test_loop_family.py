"""The SDOF hysteresis candidate's loop family has no walls (theory §1.1: the loop fitted by its turnover force,
branch coordinate and ν up to 6): the coordinates map to β, γ, δ and back exactly, the starts are the listed loop
shapes, and loops drawn at random across the whole family (ν from 1 to 6, a turnover force from a few times the
noise's to beyond the linear spring's, loading branches that soften and that harden) are named with at least 90 %
of the gap removed. The truths come from a generator independent of the FMUs (numpy draws, the CasADi reference
integrated by CVODES), never at a start or a bound of the candidate. The diagnoses are slow: `pytest -m slow`."""
import numpy as np
import pytest

from pyfit.gap import datasets
from pyfit.gap import diagnose as dg
from pyfit.gap.effect import BRANCH, TURNOVER, LoopCoordinates, Scale, branch_slopes, loop_coordinates, with_derived
from pyfit.gap.effects import (BETA_SHARE, LOOP_SHARES, SDOF_LOOP_STARTS, BRANCH_RANGE, MAX_NU, TURNOVER_RANGE,
                               candidates)

SEED = 20261208  # this file's draws
NOISE_FORCE = datasets.SDOF.noise * datasets.SDOF.linear["k"]  # the sensor noise as a spring force [N]


def _loops(n: int) -> list[dict]:
    """SDOF Bouc-Wen truths (FMU values) across the family: ν uniform in each sixth of 1-6 in turn; the element
    holding 20-70 % of the stiffness 1e5 N/m; the loading branch s = γ + δ softening (0.1 to 1.5) or, in the first
    of every six at ν up to 1.25, hardening (-1 to -0.1); unloading d = γ − δ from 0 to 2.5, a dissipating loop
    (γ > 0.05); turning over (the stronger branch's tangent changed by α) at 4 to 2000 times the noise's force
    (2 N to 1 kN: from a loop within the noise's reach to one stronger than the spring at the data's deflection),
    a hardening one from 100 times (50 N). A hardening loading branch grows without bound at a finite deflection
    when ν > 1 (Bouc-Wen's class III) and exponentially at ν = 1: a physical element hardens that way only a
    little within the data's force (the benchmark's: ν = 1, turning over at 26 N under drives of 10-50 N)."""
    rng, out = np.random.default_rng(SEED), []
    for i in range(n):
        hardening = i % 6 == 0
        nu = 1.0 + rng.uniform(0.05, 0.95) * (0.25 if hardening else (MAX_NU - 1.0) / 6) + (i % 6) * (MAX_NU - 1) / 6
        loading = (-1.0, -0.1) if hardening else (0.1, 1.5)
        s, d = rng.uniform(*loading), rng.uniform(0.0, 2.5)
        while s + d < 0.1:
            s, d = rng.uniform(*loading), rng.uniform(0.0, 2.5)
        alpha = 1e5 * rng.uniform(0.2, 0.7)
        turnover = NOISE_FORCE * 10.0 ** rng.uniform(np.log10(100.0 if hardening else 4.0), np.log10(2000.0))
        out.append({"k": 1e5 - alpha, "alpha": alpha, "beta": alpha / (max(abs(s), abs(d)) * turnover ** nu),
                    "gamma": (s + d) / 2, "delta": (s - d) / 2, "nu": nu})
    return out


def test_the_coordinates_give_the_bouc_wen_parameters_and_back():
    """β·γ and β·δ (what the data identify, theory §1.1) and the tangent ratios at the turnover force: the
    loading branch's tangent there is (1 − s)·α and the unloading's (1 + d)·α, from the Bouc-Wen law itself."""
    for loop in _loops(30):
        coords = loop_coordinates(loop["alpha"], loop["beta"], loop["gamma"], loop["delta"], loop["nu"])
        back = LoopCoordinates()({"alpha": loop["alpha"], "nu": loop["nu"], **coords})
        for n in ("gamma", "delta"):
            assert back["beta"] * back[n] == pytest.approx(loop["beta"] * loop[n], rel=1e-12)
        z, a, b, g, dl, nu = coords[TURNOVER], loop["alpha"], back["beta"], back["gamma"], back["delta"], loop["nu"]
        loading = a - b * (g * z ** nu + dl * z ** nu)  # dz/dy with y, z rising (z = F_t)
        unloading = a - b * (-g * z ** nu + dl * z ** nu)  # dz/dy with y falling, z = -F_t
        s, d = branch_slopes(coords[BRANCH])
        assert loading == pytest.approx((1.0 - s) * a, abs=1e-9 * a)  # to rounding of α
        assert unloading == pytest.approx((1.0 + d) * a, abs=1e-9 * a)
        assert max(abs(s), abs(d)) == 1.0 and BRANCH_RANGE[0] <= coords[BRANCH] <= BRANCH_RANGE[1]


def test_the_starts_are_the_listed_loop_shapes_and_inside_the_box():
    """Every start of the candidate is a listed shape (γ, δ times its width, ν) at the reference β, and every
    start and drawn truth lies inside the bounds, away from them."""
    scale = Scale(1e-3, 0.2, 1e5)
    effect = candidates("sdof")["hysteresis"]
    bounds = {p.name: p.range(scale)[::2] for p in effect.params}
    shapes = {(round(w * sh["gamma"], 9), round(w * sh["delta"], 9), sh["nu"]) for w in LOOP_SHARES
              for sh in SDOF_LOOP_STARTS}
    for start in effect.starts(scale):
        values = with_derived(start, effect.derived(scale))
        ref = (BETA_SHARE * scale.k * scale.sigma_y) ** (1 - values["nu"]) / scale.sigma_y
        w = values["beta"] / ref
        assert (round(w * values["gamma"], 9), round(w * values["delta"], 9), values["nu"]) in shapes
        assert all(bounds[n][0] < start[n] < bounds[n][1] for n in (TURNOVER, BRANCH))
    force = scale.k * scale.sigma_y
    assert TURNOVER_RANGE[0] * force < 2.0 and TURNOVER_RANGE[1] * force > 1e3  # the drawn turnover forces [N]


@pytest.mark.slow
@pytest.mark.parametrize("case", range(6))
def test_a_loop_drawn_across_the_whole_family_is_named(tmp_path, fmu_dir, case, measured):
    truth = _loops(6)[case]
    data = datasets.write_dataset(tmp_path / "data", datasets.SDOF, "hysteresis", seed=case, periods=2, truth=truth)
    rep = dg.diagnose("sdof", data, tmp_path / "out", dg.DiagnoseConfig(), fmu_dir, workers=2, progress=False)
    assert rep.chosen_name == "hysteresis", (truth, rep.sentence, rep.ranking[:2])
    measured(f"SDOF hysteresis across the whole loop family ({', '.join(f'{k} = {v:.3g}' for k, v in truth.items())}):"
             " held-out shrink [%]", rep.ranking[0].shrink_pct, 90.0, at_least=True)
