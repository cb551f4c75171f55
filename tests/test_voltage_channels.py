"""Channels recorded as voltages and channels in the wrong quantity (pyfit.io.data.check_quantities).

A shaker test without a force cell records the amplifier's drive voltage, an electronic oscillator its node
voltages: each is the model variable times a gain nobody measured. With the drive U = u/G [V] (G in N/V) and the
sensor Y = H y [V], the SDOF equation (theory §1.1) divided by G is the same equation in other units,
(m/GH) Y'' + (c/GH) Y' + (k/GH) Y + k3/(G H^3) Y^3 = U, so the diagnosis must name the same effect and its
fitted values must be the truth's divided by those factors. Here a random SDOF with a random cubic
spring is simulated by the CasADi reference, its force rewritten in V and its displacement in mV at random gains.
A force column given in mm, or a damper's channel in V (its described geometry fixes the scale), is refused with
one error naming the sidecar's field."""
import numpy as np
import pytest

from gap_cases import CI
from pyfit.gap import datasets
from pyfit.gap import diagnose as dg
from pyfit.io.data import read_measurement, write_measurement


def _rewritten(src, dst, drive_gain: float, sensor_gain: float, force_unit: str = "V", out_unit: str = "mV"):
    """Each file of `src` with its force u as the drive voltage u / drive_gain and its displacement y as the sensor
    voltage sensor_gain * y, in the given units (written to `dst`)."""
    for csv in sorted(src.glob("*.csv")):
        m = read_measurement(csv)
        volts_in = {"drive": (m.values["u_meas"] / drive_gain, force_unit, "u")}
        volts_out = {"sensor": (m.values["y_meas"] * sensor_gain, out_unit, "y")}
        write_measurement(dst / csv.name, m.model, m.t, volts_in, volts_out, level=m.level,
                          level_value=m.level_value, excitation=m.excitation, notes="drive and sensor in volts")
    return dst


@pytest.fixture(scope="module")
def random_sdof(tmp_path_factory):
    """A random SDOF (m, c, k within 0.7-1.4 of the family's) with a random cubic spring (0.5-2 x the family's
    reference), written by the CasADi reference; the drive's gain 5-50 N/V and the sensor's 100-2000 V/m."""
    rng = np.random.default_rng(20261205)
    base = {"m": 2.0 * rng.uniform(0.7, 1.4), "c": 10.0 * rng.uniform(0.7, 1.4), "k": 1e5 * rng.uniform(0.7, 1.4)}
    k3 = datasets.SDOF.withheld["cubic_stiffness"]["k3"] * float(np.exp(rng.uniform(np.log(0.5), np.log(2.0))))
    root = tmp_path_factory.mktemp("voltages")
    data = datasets.write_dataset(root / "newton", datasets.SDOF, "cubic_stiffness", seed=int(rng.integers(1 << 30)),
                                  periods=2, base=base, truth={**datasets.SDOF.withheld["cubic_stiffness"], "k3": k3})
    gains = float(rng.uniform(5.0, 50.0)), float(rng.uniform(100.0, 2000.0))
    return root, data, {**base, "k3": k3}, gains


def test_an_sdof_driven_and_recorded_in_volts_is_diagnosed_in_the_units_the_gains_define(random_sdof, fmu_dir,
                                                                                          measured):
    root, data, truth, (G, H) = random_sdof
    volts = _rewritten(data, root / "volts", G, H)
    rep = dg.diagnose("sdof", volts, root / "out", CI, fmu_dir, workers=2, progress=False)
    assert rep.chosen_name == "cubic_stiffness", rep.sentence
    assert rep.voltage_channels == ("drive (u)", "sensor (y)")
    fitted = rep.ranking[0].params
    # each fitted value times its gains is the truth's (SI); the natural frequency carries no gain
    measured("SDOF in volts (drive 5-50 N/V, sensor 100-2000 V/m, random): |k3' G H^3 / k3 - 1|",
             abs(fitted["k3"] * G * H ** 3 / truth["k3"] - 1.0), 0.02)
    measured("SDOF in volts: |k' G H / k - 1|", abs(fitted["k"] * G * H / truth["k"] - 1.0), 0.01)
    measured("SDOF in volts: |sqrt(k'/m') / sqrt(k/m) - 1|",
             abs(np.sqrt(fitted["k"] / fitted["m"]) / np.sqrt(truth["k"] / truth["m"]) - 1.0), 0.005)
    assert "Recorded as voltages: drive (u), sensor (y)" in (root / "out" / "report.md").read_text()


def test_a_force_column_in_a_length_unit_is_refused_naming_the_field(random_sdof, fmu_dir, tmp_path):
    root, data, _, _ = random_sdof
    wrong = _rewritten(data, tmp_path / "mm", 1.0, 1.0, force_unit="mm", out_unit="m")
    with pytest.raises(dg.DiagnoseError) as err:
        dg.diagnose("sdof", wrong, tmp_path / "out", CI, fmu_dir, workers=1, progress=False)
    msg = str(err.value)
    assert "level1" in msg and ".toml" in msg and "[inputs.drive.unit]" in msg, msg
    assert "'mm' measures length; model_variable 'u' is force (N)" in msg, msg
    assert "allowed: N, mN, daN, kN, lbf, V, mV" in msg, msg


def test_a_damper_channel_in_volts_is_refused(fmu_dir, tmp_path):
    """The damper's described masses and arms fix its scale: a voltage must be converted by its sensitivity."""
    t = np.arange(400) / 200.0
    x = 1e-4 * np.sin(2 * np.pi * 5.0 * t)
    for i in (1, 2, 3):
        write_measurement(tmp_path / "data" / f"level{i}.csv", "StockbridgeDamper", t, {"x": (i * x, "mm", "x_base")},
                          {"acc": (i * x, "V", "acc_x1")}, level_value=float(i))
    with pytest.raises(dg.DiagnoseError) as err:
        dg.diagnose("damper", tmp_path / "data", tmp_path / "out", CI, fmu_dir, workers=1, progress=False)
    msg = str(err.value)
    assert "[outputs.acc.unit]" in msg and "'V' measures voltage; model_variable 'acc_x1' is acceleration" in msg
    assert "give the sensor's sensitivity, e.g. sensitivity = \"100 mV/g\"" in msg, msg
    assert "allowed: m/s2, cm/s2, mm/s2, in/s2, ft/s2, g, mg" in msg, msg
    assert "\n" not in msg
