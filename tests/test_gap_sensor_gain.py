"""A gain between the input and output channels (a sensor's sensitivity off by a per cent or so): the candidate
sensor_gain of the damper, which multiplies every output the model gives and is offered only where the
diagnosis's effects name it; on a null damper case whose accelerometers read a gain drawn at random, it is named
and the gain recovered (-m slow)."""
import dataclasses

import numpy as np
import pytest

from pyfit.gap import datasets
from pyfit.gap import diagnose as dg
from pyfit.gap import simulate as sim
from pyfit.gap.systems import make_system

def _drawn(seed: int) -> tuple[float, int]:
    """A gain drawn at random, 0.8-2.5 % of either sign (never the candidate's start, 0), and a noise seed."""
    rng = np.random.default_rng(seed)
    return float(rng.choice([-1.0, 1.0]) * rng.uniform(0.008, 0.025)), int(rng.integers(1 << 30))


def test_the_gain_multiplies_every_output_and_reaches_no_fmu_parameter(runner):
    """The damper driven by a 2 s clamp sine: with sensor_gain g every output is (1 + g) times the one without,
    to rounding (the FMU, which has no such parameter, never sees it)."""
    fs, (g, _) = 500.0, _drawn(20261207)
    t = np.arange(1000) / fs
    w = 2 * np.pi * 12.0
    motion = {"x_base": 1e-3 * np.sin(w * t), "v_base": 1e-3 * w * np.cos(w * t),
              "a_base": -1e-3 * w**2 * np.sin(w * t)}
    rec = sim.Record("r", "r", 1.0, fs, motion, {"acc_x1": np.zeros(1000), "x2": np.zeros(1000)}, 0)
    fmu = runner("StockbridgeDamper")
    plain, scaled = (sim.simulate(fmu, rec, {"exc_type": 0, **extra}) for extra in ({}, {"sensor_gain": g}))
    for k in rec.outputs:
        # (1 + g) times, to rounding: the gain multiplies the record before its mean is taken out
        assert np.allclose(scaled[k], (1 + g) * plain[k], rtol=1e-12, atol=1e-12 * np.std(plain[k]))
        assert np.std(plain[k]) > 0


def test_sensor_gain_is_a_candidate_only_where_the_effects_name_it():
    system = make_system("damper", {}, None)
    default = dg.tried_effects(system, dg.DiagnoseConfig())
    assert "sensor_gain" in system.effects and "sensor_gain" not in default and "sensor_delay" in default
    asked = dg.tried_effects(system, dataclasses.replace(dg.DiagnoseConfig(), effects=default + ["sensor_gain"]))
    assert asked == default + ["sensor_gain"]


@pytest.mark.slow  # about two minutes on two cores: the reference writes the sweeps, the diagnosis refits
def test_a_gain_between_the_channels_is_named_sensor_gain(tmp_path, fmu_dir, measured):
    """A null case of the reference damper (CasADi reference, a lab's sensor chain; 12 s clamp-acceleration
    sweeps at three levels, both masses' accelerometers), the accelerometers' readings multiplied by a gain drawn
    at random: with sensor_gain among the effects the diagnosis names it and finds the gain to within the
    decimation filter's passband gain over the band (at most 0.28 %, python bench/sensor_chain.py's filter),
    which the outputs carry and the clamp motion does not."""
    g, seed = _drawn(20261206)
    data = datasets.write_dataset(tmp_path / "data", datasets.DAMPER, "none", seed=seed,
                                  style=datasets.LabStyle("sweep", ("acc_x1", "acc_x2"), "a", record_s=12.0))
    for csv in sorted(data.glob("*.csv")):
        head, *rows = csv.read_text().splitlines()
        names = head.split(",")
        values = np.array([[float(v) for v in r.split(",")] for r in rows])
        for name in ("acc_x1_meas", "acc_x2_meas"):
            values[:, names.index(name)] *= 1 + g
        np.savetxt(csv, values, delimiter=",", header=head, comments="", fmt="%.17g")
    system = make_system("damper", {}, None)
    default = dg.DiagnoseConfig()
    cfg = dataclasses.replace(default, effects=dg.tried_effects(system, default) + ["sensor_gain"])
    rep = dg.diagnose("damper", data, tmp_path / "out", cfg, fmu_dir, workers=2, progress=False)
    assert rep.chosen_name == "sensor_gain", (rep.sentence, rep.ranking[:2])
    fitted = next(r.params["sensor_gain"] for r in rep.ranking if r.effect == "sensor_gain")
    measured(f"damper null case, accelerometers reading {100 * g:+.2f} % off: |fitted sensor_gain − gain|",
             abs(fitted - g), 0.003)
