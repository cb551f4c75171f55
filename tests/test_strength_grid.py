"""When no model explains the data, the best ones are refitted from the best point of a grid over their members'
strengths (systems.strength_grid): a hardening spring with a weak quadratic damper on a sweep, where both set
the frequency at which the response jumps down and the calibration misfit has a narrow valley in the pair's
strengths (that refit under -m slow). The truth is case 121 of the campaign's random draw (seed 18: the CasADi reference, lab-style
files), on which the forward selection's joint refit stopped at the spring alone."""
import dataclasses

import numpy as np
import pytest

from pyfit.gap import campaign, datasets, localise, selection
from pyfit.gap import diagnose as dg
from pyfit.gap import simulate as sim
from pyfit.gap.attribute import effect_task, nominal_task, run_fit
from pyfit.gap.effect import combine
from pyfit.gap.systems import strength_grid


def test_the_grid_spans_each_members_strengths_and_holds_the_refit(sdof_system):
    _, system = sdof_system
    scale = system.scale([np.sin(np.linspace(0, 60, 3000)) * 1e-3], 500.0, {})
    members = [system.effects["cubic_stiffness"], system.effects["quadratic_damping"]]
    grid = strength_grid(members, scale, {"k3": 2.5e8, "c2": 0.0, "k": 1e5})
    k3_lo, _, k3_hi = members[0].params[0].range(scale)
    _, _, c2_hi = members[1].params[0].range(scale)
    k3s, c2s = sorted({p["k3"] for p in grid}), sorted({p["c2"] for p in grid})
    # k3: 9 near its refit, 9 towards each end of its symmetric range, zero; c2 (refit at zero, range from
    # zero up): 9 towards its upper end, zero; every pair of them; no other parameter moved
    assert len(k3s) == 28 and len(c2s) == 10 and len(grid) == 280 and all(set(p) == {"k3", "c2"} for p in grid)
    assert min(abs(k / 2.5e8 - 1) for k in k3s) < 1e-12 and 0.0 in k3s and 0.0 in c2s
    assert k3s[0] == pytest.approx(k3_lo) and k3s[-1] == pytest.approx(k3_hi) and c2s[-1] == pytest.approx(c2_hi)
    assert min(c for c in c2s if c > 0) == pytest.approx(1e-4 * c2_hi)


@pytest.mark.slow  # about 25 s of FMU runs: a nominal fit, a refit and the grid's refit
def test_a_spring_and_damper_setting_a_sweeps_jump_are_found_from_the_grid(tmp_path, sdof_system,
                                                                          measured):
    runner, system = sdof_system
    fmu = runner.path
    case = campaign.draw(200, 18)[121]
    assert case.withheld == "cubic_stiffness+quadratic_damping" and case.excitation == "sweep"
    style = datasets.LabStyle(case.excitation, tuple(case.outputs), case.motion, record_s=campaign.RECORD_S)
    data = datasets.write_dataset(tmp_path / "data", datasets.SDOF, case.withheld, seed=case.seed,
                                  periods=campaign.PERIODS, style=style, truth=case.truth)
    loaded = dg._load(data, system, dg.DiagnoseConfig(), runner)
    cfg = dg.with_drive(dg.DiagnoseConfig(), system, loaded.rate)
    records, cal, held = loaded.records, loaded.cal, loaded.held
    nominal = run_fit(nominal_task(system, fmu, cal, cfg.nominal_budget, cfg.upsample, threads=2))
    moved = [sim.simulate(runner, r, nominal.params, cfg.upsample, system.lead_periods,
                          outputs=system.deflection_outputs) for r in cal]
    scale = system.scale([system.deflection(m, r) for m, r in zip(moved, cal)], cal[0].fs, nominal.params)
    members = [system.effects["cubic_stiffness"], system.effects["quadratic_damping"]]
    spring = run_fit(dataclasses.replace(effect_task(system, members[0], fmu, cal, nominal, scale,
                                                     cfg.refit_budget, cfg.upsample), threads=2))

    def held_out(params):
        return selection.heldout_nrmse({r.name: sim.simulate(runner, r, params, cfg.upsample, system.lead_periods)
                                        for r in held}, held)

    floor = localise.noise_estimates(records)[held[0].name][0]
    explained_below = selection.explained_below(floor, cfg.explain_factor, cfg.explain_margin)
    assert held_out(spring.params) > 3 * explained_below  # the spring alone: the sweep jumps elsewhere
    at_spring = {**spring.params, "c2": 0.0}  # the pair where the forward selection left it
    task = effect_task(system, combine(members), fmu, cal, nominal, scale, cfg.refit_budget, cfg.upsample,
                       seeds=(at_spring,))
    pair = run_fit(dataclasses.replace(task, start=task.alternatives[-1], basin=None, threads=2,
                                       alternatives=strength_grid(members, scale, at_spring)))
    assert held_out(pair.params) <= explained_below
    for name in ("k3", "c2"):
        measured(f"campaign case 121 (spring + damper on a sweep), {name} from the grid's refit: |fit / truth - 1|",
                 abs(pair.params[name] / case.truth[name] - 1), 0.02)
