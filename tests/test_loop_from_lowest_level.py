"""A loop refit also starts from the linear system of the lowest level, where a hysteretic element has barely
yielded: there the element's small-amplitude stiffness k + alpha is that level's stiffness, not the nominal's
compromise over every level, so the loop starts are scaled to it (attribute.effect_task). The truth of the
second test is case 20 of the campaign's random draw (seed 18: a sharp loop, ν near 3, under band-limited noise,
written by the CasADi reference as a lab writes it), on which the loop's refit from the nominal's stiffness alone
stopped far above the noise floor."""
import dataclasses
import json

import numpy as np
import pytest

from pyfit.gap import campaign, datasets, selection
from pyfit.gap import diagnose as dg
from pyfit.gap import simulate as sim
from pyfit.gap.attribute import Fit, effect_task, nominal_task, run_fit
from pyfit.runtime.linearize import linear_modes


def test_loop_starts_from_a_linear_start_hold_its_stiffness(sdof_system):
    """Every loop start descended from the lowest level's linear system (m, c, k) has that m and c and splits
    that k between k and alpha; a cubic spring's starts keep their share k3·σ_y²/k of that stiffness."""
    _, system = sdof_system
    scale = system.scale([1e-3 * np.sin(np.linspace(0, 60, 3000))], 500.0, {"k": 5e4})
    nominal = Fit("nominal", {**system.nominal_fixed, "m": 1.5, "c": 20.0, "k": 5e4}, ["m", "c", "k"], 0, 0.1, 1, 0.0)
    lowest = {"m": 2.0, "c": 10.0, "k": 1.2e5}
    loop = effect_task(system, system.effects["hysteresis"], "x.fmu", [], nominal, scale, 100, 4,
                       linear_starts=(lowest,))
    from_lowest = [a for a in loop.alternatives if a.get("m") == lowest["m"]]
    shapes = system.effects["hysteresis"].starts(scale)
    assert len(from_lowest) == len(shapes) + 1  # each shape and the default start
    for a in from_lowest:
        assert a["c"] == lowest["c"] and a["k"] + a["alpha"] == pytest.approx(lowest["k"], rel=1e-12)
    # the nominal's own starts keep the nominal's stiffness
    assert all(a["k"] + a["alpha"] == pytest.approx(5e4, rel=1e-12) for a in loop.alternatives if "m" not in a)
    spring = effect_task(system, system.effects["cubic_stiffness"], "x.fmu", [], nominal, scale, 100, 4,
                         linear_starts=(lowest,))
    shares = sorted(a["k3"] * scale.sigma_y ** 2 / a["k"] for a in spring.alternatives
                    if a.get("m") == 2.0 and a["k3"])
    nominal_shares = sorted(a["k3"] * scale.sigma_y ** 2 / 5e4 for a in spring.alternatives if "m" not in a)
    assert len(shares) == len(nominal_shares) > 0 and shares == pytest.approx(nominal_shares, rel=1e-12)


@pytest.mark.slow
def test_a_sharp_loop_under_noise_is_refitted_to_the_truth_s_misfit(tmp_path, sdof_system, measured):
    """Campaign case 20: the loop's refit (every start, from the nominal's and from the lowest level's linear
    system) ends within 1.2 times the truth's own held-out misfit (the FMU at the CasADi reference's parameters);
    with the lowest level's starts at the nominal's stiffness it stopped far above it."""
    runner, system = sdof_system
    case = campaign.draw(200, 18)[20]
    assert case.withheld == "hysteresis" and case.excitation == "noise" and case.truth["nu"] > 2.9
    style = datasets.LabStyle(case.excitation, tuple(case.outputs), case.motion, record_s=campaign.RECORD_S)
    data = datasets.write_dataset(tmp_path / "data", datasets.SDOF, case.withheld, seed=case.seed,
                                  periods=campaign.PERIODS, style=style, truth=case.truth)
    cfg = dg.DiagnoseConfig()
    records, cal, held, *_ = dg._load(data, system, cfg, runner)
    nominal = run_fit(nominal_task(system, runner.path, cal, cfg.nominal_budget, cfg.upsample, threads=2))
    moved = [sim.simulate(runner, r, nominal.params, cfg.upsample, system.lead_periods,
                          outputs=system.deflection_outputs) for r in cal]
    scale = system.scale([system.deflection(m, r) for m, r in zip(moved, cal)], cal[0].fs, nominal.params)
    lowest = min(cal, key=lambda r: r.level_value)
    linear = tuple(system.data_starts([lowest], lambda p: linear_modes(runner.path, p)))
    loop = run_fit(dataclasses.replace(effect_task(system, system.effects["hysteresis"], runner.path, cal, nominal,
                                                   scale, cfg.refit_budget, cfg.upsample, linear_starts=linear),
                                       threads=2))

    def held_out(params):
        return selection.heldout_nrmse({r.name: sim.simulate(runner, r, params, cfg.upsample, system.lead_periods)
                                        for r in held}, held)

    truth = held_out({**nominal.params, **json.loads((data / "truth.json").read_text())["params"]})
    measured("campaign case 20 (sharp loop, band-limited noise): loop refit's held-out NRMSE over the truth's",
             held_out(loop.params) / truth, 1.2)
