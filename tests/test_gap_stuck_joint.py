"""A damper whose joints stick: friction about as large as the force that carries each end mass at the clamp's
acceleration at the lowest level (the arms move nearly with the clamp there and slip at the highest level).
Geometry, friction forces, sensors and clamp channels are drawn at random (numpy); the truth is simulated by the
independent CasADi reference and written as lab files (band-limited noise, anti-alias filter, sensor noise).

The linear nominal can then only fit the lowest level with a heavily damped messenger; a calibration that scans
the stiffness alone ends at a soft, isolated one instead, and a friction range scaled by that nominal's
deflection (0.5 k σ_y) lies far below the truth. Both are checked here: the diagnosis names the friction and
recovers its forces. Slow seeds: `python -m pytest -m slow tests/test_gap_stuck_joint.py`."""
import dataclasses
import json

import numpy as np
import pytest

from pyfit.analysis.excitation import band_noise, motion_with_derivatives
from pyfit.gap import datasets
from pyfit.gap import diagnose as dg
from pyfit.gap.campaign import DAMPER_MOTIONS, DAMPER_OUTPUTS, damper_geometry
from pyfit.gap.effect import Scale
from pyfit.gap.effects import candidates
from pyfit.gap.systems import FAMILY
from pyfit.io.nominal import NominalModel

RECORD_S = 6.0
# a competitor of each kind: a damping that grows with amplitude, a stiffness that does
EFFECTS = ["coulomb_friction", "quadratic_damping", "cubic_stiffness"]


def _stuck_joint_case(seed: int):
    """A random damper and friction forces F_c,i = u_i m_i a_rms (u_i uniform 0.5-1.5; a_rms the lowest level's
    clamp acceleration RMS), recorded on band-limited noise over the damper's test band."""
    rng = np.random.default_rng(seed)
    base, band = damper_geometry(rng)
    t = np.arange(int(RECORD_S * datasets.DAMPER.fs)) / datasets.DAMPER.fs
    noise_seed = int(rng.integers(1 << 30))
    lowest = band_noise(*band, datasets.DAMPER.levels[0], noise_seed)  # the clamp displacement [m]
    clamp = motion_with_derivatives(lowest, t, ("x", "v", "a"))["a"]
    a_rms = float(np.sqrt(np.mean(clamp ** 2)))
    friction = {f"F_c{i}": float(rng.uniform(0.5, 1.5) * base[f"m{i}"] * a_rms) for i in (1, 2)}
    style = datasets.LabStyle("noise", DAMPER_OUTPUTS[rng.integers(len(DAMPER_OUTPUTS))],
                              str(rng.choice(DAMPER_MOTIONS)), record_s=RECORD_S)
    return base, band, {**friction, "v_s": 1e-3}, style, noise_seed


@pytest.mark.parametrize("seed", [pytest.param(s, marks=pytest.mark.slow) if s else s for s in range(3)])
def test_a_damper_joint_stuck_at_the_lowest_level_is_named_and_its_friction_recovered(tmp_path, fmu_dir, seed,
                                                                                      measured):
    base, band, truth, style, noise_seed = _stuck_joint_case(seed)
    family = dataclasses.replace(datasets.DAMPER, band_hz=band)
    data = datasets.write_dataset(tmp_path / "data", family, "coulomb_friction", seed=noise_seed, style=style,
                                  base=base, truth=truth)
    # the user describes the geometry; the messenger's EI and damping are calibrated
    described = NominalModel("damper", {k: v for k, v in base.items() if k not in ("EI", "alpha_pd", "beta_pd")})
    rep = dg.diagnose("damper", data, tmp_path / "out", dg.DiagnoseConfig(effects=EFFECTS), fmu_dir, workers=2,
                      progress=False, nominal=described)
    assert rep.chosen_name == "coulomb_friction", (rep.sentence, style, truth,
                                                        [(r.effect, r.shrink_pct) for r in rep.ranking])
    fit = json.loads((tmp_path / "out" / "fits" / "coulomb_friction.json").read_text())["fit"]["params"]
    error = max(abs(fit[k] / truth[k] - 1.0) for k in ("F_c1", "F_c2"))
    measured(f"stuck damper joint (seed {seed}, {'+'.join(style.outputs)}, clamp {style.motion}): friction "
             "forces recovered, max relative error", error, 0.05)


def test_the_friction_range_reaches_the_force_of_a_stuck_joint():
    class Rec:  # a record's compared clamp acceleration
        def __init__(self, a):
            self.a = a

        def compared(self, name):
            assert name == "a_base"
            return self.a

    rng = np.random.default_rng(7)
    m1, m2 = rng.uniform(0.5, 4.0, 2)
    records = [Rec(rng.normal(0.0, s, 500)) for s in rng.uniform(0.1, 2.0, 3)]
    peak = max(np.max(np.abs(r.a)) for r in records)
    stuck = FAMILY["damper"].stuck_force(records, {"m1": m1, "m2": m2})
    assert stuck == pytest.approx(max(m1, m2) * peak, rel=1e-15)
    friction = candidates("damper")["coulomb_friction"].params[0]
    # a soft nominal's spring force at its deflection scale (0.5 k σ_y) far below it: the stuck force bounds
    assert friction.range(Scale(1e-4, 1e-2, 10.0, {}, stuck)) == (0.0, 0.0, stuck)
    # a stiff nominal's above it: its spring force does
    assert friction.range(Scale(1e-3, 1e-1, 1e4 * stuck, {}, stuck)) == (0.0, 0.0, pytest.approx(5.0 * stuck))
