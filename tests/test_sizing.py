"""Withheld effects drawn at a size over the sensor noise (pyfit.gap.sizing): the loop scaled as a whole is the
same loop times the gain (the Bouc-Wen law integrated here with scipy), and a case's records show each effect at
the size drawn for it (the CasADi reference through pyfit.gap.datasets)."""
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from pyfit.gap import campaign, datasets, effects, sizing


def _loop_force(p: dict, amplitude: float, omega: float, t: np.ndarray) -> np.ndarray:
    """z(t) of dz/dt = α ẏ - β (γ |ẏ| |z|^(ν-1) z + δ ẏ |z|^ν) under y = amplitude sin(ω t), from z = 0."""
    def rate(tt, z):
        v = amplitude * omega * np.cos(omega * tt)
        az = abs(z[0])
        return [p["alpha"] * v - p["beta"] * (p["gamma"] * abs(v) * az ** (p["nu"] - 1) * z[0]
                                              + p["delta"] * v * az ** p["nu"])]
    return solve_ivp(rate, (0.0, t[-1]), [0.0], t_eval=t, method="LSODA", rtol=1e-10, atol=1e-12).y[0]


def test_a_loop_scaled_as_a_whole_is_the_same_loop_times_the_gain():
    """Loops drawn across the family and gains drawn over the range the sizing uses: z/g of the scaled loop follows
    the drawn loop's z to the integrator's tolerance, at an amplitude where the drawn loop turns over (its force
    at least 3 x the linear part α y would leave it short of, so the law's nonlinear terms carry the result)."""
    rng = np.random.default_rng(20261204)
    t = np.linspace(0.0, 0.2, 801)  # two cycles at 10 Hz
    for _ in range(4):
        loop = effects.hysteresis_loop(rng)
        gain = float(np.exp(rng.uniform(np.log(0.01), np.log(1.5))))
        gain = min(gain, sizing.max_gain(loop, "sdof", "hysteresis"))
        z_y = (loop["alpha"] / loop["beta"]) ** (1.0 / loop["nu"])  # the force where the loop turns over [N]
        amplitude = 5.0 * z_y / loop["alpha"]
        z = _loop_force(loop, amplitude, 2 * np.pi * 10.0, t)
        scaled = sizing.scaled(loop, "sdof", {"hysteresis": gain})
        assert scaled["k"] + scaled["alpha"] == pytest.approx(effects.SDOF_STIFFNESS)
        assert np.max(np.abs(loop["alpha"] * amplitude * np.sin(2 * np.pi * 10.0 * t) - z)) > 3 * z_y
        z_scaled = _loop_force(scaled, amplitude, 2 * np.pi * 10.0, t)
        assert np.max(np.abs(z_scaled / gain - z)) < 1e-6 * np.max(np.abs(z))


@pytest.mark.parametrize("index", [0, 1])
def test_a_drawn_case_is_written_with_its_effects_at_the_sizes_drawn(index):
    """The first two SDOF stepped-sine cases of a draw (seed 11): a cubic spring whose drawn strength shows at
    20 x its drawn size, and a loop with a quadratic damping, at 8.8 x and 0.65 x theirs. Scaled in the rounds a
    campaign uses, the records written last show each effect within 25 % of its size (the summary's size bins are
    2-2.5 x wide): measured 2.2 % (spring), 5.1 % and 6.3 % (the pair's loop and damping)."""
    case = [c for c in campaign.draw(30, seed=11) if c.sizes and c.excitation == "stepped_sine"][index]
    family = datasets.FAMILIES["sdof"]
    style = datasets.LabStyle(case.excitation, case.outputs, record_s=campaign.RECORD_S)

    def sizes_of(truth):
        return datasets.effect_sizes(family, case.withheld, seed=case.seed, style=style, truth=truth)

    at_reference = sizes_of(case.truth)
    assert max(at_reference[e] / case.sizes[e] for e in case.sizes) > 5
    got = sizes_of(sizing.sized(case.truth, "sdof", case.sizes, sizes_of))
    for effect, wanted in case.sizes.items():
        assert sizing.SIZE_RANGE[0] <= wanted <= sizing.SIZE_RANGE[1]
        assert got[effect] == pytest.approx(wanted, rel=0.25)


def test_a_case_s_records_are_the_same_whether_its_truths_are_simulated_again_or_reused(tmp_path, monkeypatch):
    """A drawn SDOF case with a cubic spring, written as a campaign writes it (sized in rounds, 1.5 s records): the
    spring's tangent truth (the spring off) is the same in every round, so the reference simulates it once, and
    the files are byte for byte those written when every truth is simulated again."""
    case = next(c for c in campaign.draw(60, seed=11) if c.withheld == "cubic_stiffness" and c.excitation == "noise")
    calls = []
    simulate = datasets.simulate_truth
    monkeypatch.setattr(datasets, "simulate_truth", lambda spec: calls.append(spec.params) or simulate(spec))
    written = {}
    for kept in (datasets.TRUTHS_KEPT, 0):
        monkeypatch.setattr(datasets, "TRUTHS_KEPT", kept)
        datasets._truths.clear()
        calls.clear()
        _, data, _ = campaign.write_case(case, tmp_path / f"kept{kept}", record_s=1.5)
        written[kept] = ({p.name: p.read_bytes() for p in sorted(data.glob("level*"))}, len(calls),
                         sum(c["k3"] == 0.0 for c in calls))
    (reused, n_reused, tangent_reused), (again, n_again, tangent_again) = written.values()
    assert reused == again and len(reused) == 6
    levels, rounds = 3, sizing.ROUNDS + 1  # the sizing's rounds and the records written last
    assert (n_again, tangent_again) == (2 * levels * rounds, levels * rounds)
    assert (n_reused, tangent_reused) == (levels * (rounds + 1), levels)
