"""A built-in effect is one declaration (pyfit.gap.effects): a dummy added that way is switched off in the nominal,
drawn, written, sized, screened, refitted and named by a two-case campaign; and the registry's derived tables are
what each declaration says."""
import json
import subprocess
import sys

import pytest

from pyfit.gap import datasets, effects
from pyfit.gap.systems import FAMILY

# The dummy: a hardening-only spring on the SDOF's existing cubic element (the Modelica element is there: k3), declared
# in one entry; the campaign offers the diagnosis it and the two damping candidates, not cubic_stiffness (the same
# element: the data could not tell the two apart).
SCRIPT = r'''
import json, sys
from pyfit.gap import effects
from pyfit.gap.effect import Builtin, Effect, Param

truth = {"k3": 2e8}
effects.SDOF["stiffening_spring"] = Builtin(
    Effect("stiffening_spring", (Param("k3", lambda s: (0.0, 0.0, 0.3 * s.k / s.sigma_y**2)),),
           signature="a resonance rising with amplitude"),
    off={"k3": 0.0}, truth=truth, tangent={"k3": 0.0}, strengths=("k3",),
    draw=lambda rng, factor: {"k3": truth["k3"] * factor})

from distributed import Client, LocalCluster
from pyfit.gap import campaign
from pyfit.gap.systems import FAMILY

def wanted(seed):  # two cases, each withholding the dummy at 5 x the noise or more
    cases = campaign.draw(2, seed, excitation="sweep")
    return all(c.withheld == "stiffening_spring" and c.sizes["stiffening_spring"] >= 5 for c in cases)

seed = next(s for s in range(2000) if wanted(s))
out, fmus, config = sys.argv[1:4]
with LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None) as lc, \
        Client(lc) as client:
    summary = campaign.run(2, out, fmus, seed, scheduler=client, progress=False, config=config,
                           excitation="sweep", record_s=4.0)
print(json.dumps({"seed": seed, "switched_off": FAMILY["sdof"].switches.get("k3"),
                  "candidate": "stiffening_spring" in FAMILY["sdof"].effects,
                  "top1": summary["top1"], "confusion": summary["confusion"]}))
'''


def test_an_effect_added_by_one_declaration_runs_through_a_campaign(tmp_path, fmu_dir):
    config = tmp_path / "diagnose.toml"
    config.write_text('[diagnose]\neffects = ["stiffening_spring", "coulomb_friction", "quadratic_damping"]\n'
                      "nominal_budget = 30\nrefit_budget = 60\nbeam = 1\npartners = 2\n")
    run = subprocess.run([sys.executable, "-c", SCRIPT, str(tmp_path / "campaign"), str(fmu_dir), str(config)],
                         capture_output=True, text=True, timeout=900)
    assert run.returncode == 0, run.stderr[-3000:]
    got = json.loads(run.stdout.strip().splitlines()[-1])
    assert got["switched_off"] == 0.0 and got["candidate"]  # the nominal has it off, the diagnosis offers it
    assert got["confusion"]["stiffening_spring"]["stiffening_spring"] == 2, got
    assert got["top1"] == 1.0
    for k in (0, 1):  # each case's report ranks it first, screened and refitted
        report = json.loads((tmp_path / "campaign" / f"case{k:04d}" / "diagnosis" / "report.json").read_text())
        best = report["ranking"][0]
        assert best["effect"] == "stiffening_spring" and best["screening_explained"] > 0.0, best
        assert best["shrink_pct"] >= 80.0, best


@pytest.mark.parametrize("family", ["sdof", "damper"])
def test_the_derived_tables_are_the_declarations(family):
    """The nominal's switches, the generator's truths and tangent, the campaign's draws and the peers' terms are
    each read from the declarations, nothing else."""
    declared = effects.BUILTINS[family]
    for name, b in declared.items():
        assert FAMILY[family].effects[name] is b.candidate
        assert all(FAMILY[family].switches[k] == v for k, v in b.off.items())
        if b.truth:
            assert datasets.FAMILIES[family].withheld[name] is b.truth
    assert set(datasets.FAMILIES[family].withheld) == {n for n, b in declared.items() if b.truth} | {"none"}
    assert effects.drawn(family) == tuple(n for n, b in declared.items() if b.draw)
    assert set(effects.peer_terms(family).values()) <= set(declared)
