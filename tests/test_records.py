"""Records as a user brings them, prepared for the diagnosis: a segment cut from a long record, a clamp
motion recorded as one quantity only, channels that are not FMU variables."""
import time

import numpy as np
import pytest

from pyfit.analysis.excitation import Excitation
from pyfit.gap import simulate as sim
from pyfit.gap.diagnose import DiagnoseError, diagnose
from pyfit.io.data import read_measurement, write_measurement
from pyfit.reference.synthetic import SyntheticSpec, simulate_truth

TRUTH = {"m": 2.0, "c": 10.0, "k": 1e5, "alpha": 0.0}  # 35.6 Hz, zeta 1.1 %: time constant 0.41 s


def test_segment_cut_from_a_long_record_is_compared_after_its_transient(tmp_path, runner, measured):
    fs = 500.0
    exc = Excitation(2, 50.0, 20.0, 50.0, 1.5)  # force sweep through the resonance, from rest
    t, y, u = simulate_truth(SyntheticSpec("SDOFBoucWen", exc, 20.0, fs, ["y"], TRUTH, oversample=10,
                                           passband_ripple_db=0.005))
    cut = slice(int(4 * fs), len(t))  # starts at 4 s, in full motion (16 s: a quarter is the 4 s window)
    path = write_measurement(tmp_path / "seg.csv", "SDOFBoucWen", t[cut] - t[cut][0], {"F": (u["u"][cut], "N", "u")},
                             {"Y": (y["y"][cut], "m", "y")})
    rec = sim.record_of(read_measurement(path), transient_s=4.0)
    assert rec.first == int(4.0 * fs) and rec.n == len(t[cut]) - rec.first
    out = sim.simulate(runner("SDOFBoucWen"), rec, {**TRUTH, "exc_type": 0})
    err = np.sqrt(np.mean((out["y"] - rec.outputs["y"]) ** 2) / np.mean(rec.outputs["y"] ** 2))
    # the start-up transient decays as exp(-t/0.41 s): 6e-5 of the motion after 4 s; the rest is the spline
    # upsampling of the 500 Hz input and the sensor chain (0.005 dB anti-alias filter: 6e-4)
    measured("segment cut from a long SDOF record (from 4 s, not at rest), simulated from rest with the truth, "
             "first 4 s dropped: NRMSE", err, 2e-3)


def test_clamp_motion_recorded_as_displacement_only_gives_all_three(tmp_path):
    fs, f = 500.0, 12.0
    t = np.arange(int(10 * fs)) / fs
    x = 2e-4 * np.sin(2 * np.pi * f * t) * np.minimum(t / 2, 1) ** 3
    path = write_measurement(tmp_path / "d.csv", "StockbridgeDamper", t, {"X": (x, "mm", "x_base")},
                             {"Y": (x, "m", "x1")})
    rec = sim.record_of(read_measurement(path), ("x_base", "v_base", "a_base"))
    assert set(rec.inputs) == {"x_base", "v_base", "a_base"} and rec.derived == ("v_base", "a_base")
    steady = t > 3
    w = 2 * np.pi * f
    v_ref, a_ref = 2e-4 * w * np.cos(w * t), -2e-4 * w**2 * np.sin(w * t)
    for name, ref in (("v_base", v_ref), ("a_base", a_ref)):  # RMS over the steady part (edges ring briefly)
        err = np.sqrt(np.mean((rec.inputs[name][steady] - ref[steady]) ** 2) / np.mean(ref[steady] ** 2))
        assert err < 5e-3, (name, err)


def test_a_channel_that_is_not_an_fmu_variable_is_refused(tmp_path, fmu_dir):
    fs = 500.0
    t = np.arange(int(4 * fs)) / fs
    ramp = np.minimum(t, 1.0) ** 3  # from rest
    for i, amp in enumerate((1.0, 2.0)):
        write_measurement(tmp_path / f"l{i}.csv", "SDOFBoucWen", t, {"F": (amp * ramp * np.sin(220 * t), "N", "u")},
                          {"Y": (1e-5 * amp * ramp * np.sin(220 * t), "m", "y_mass")}, level_value=amp)
    with pytest.raises(DiagnoseError, match=r"l0.toml: \[outputs\] model_variable 'y_mass' is not a variable of "
                                            r"SDOFBoucWen; allowed: F, a, v, y, z"):
        diagnose("sdof", tmp_path, tmp_path / "out", fmu_dir=fmu_dir, progress=False)


def test_sensor_offsets_are_not_dynamics(tmp_path, runner, measured):
    """A displacement transducer's rest reading (5 mm, some 30 × the vibration), a DC accelerometer's 1 g and a
    load cell's zero (20 N, some 15 × the force RMS) change neither the records the diagnosis simulates and
    compares nor the residual of the true model, nor whether the record counts as starting at rest."""
    fs = 500.0
    exc = Excitation(2, 50.0, 20.0, 50.0, 1.5)
    t, y, u = simulate_truth(SyntheticSpec("SDOFBoucWen", exc, 8.0, fs, ["y", "a"], TRUTH, oversample=10,
                                           passband_ripple_db=0.005))
    recs = []
    for name, du, dy, da in (("zeroed", 0.0, 0.0, 0.0), ("offsets", 20.0, 5e-3, 9.80665)):
        path = write_measurement(tmp_path / f"{name}.csv", "SDOFBoucWen", t, {"F": (u["u"] + du, "N", "u")},
                                 {"Y": (y["y"] + dy, "mm", "y"), "A": (y["a"] + da, "g", "a")})
        recs.append(sim.record_of(read_measurement(path)))
    assert recs[1].first == recs[0].first  # the offsets do not make the record look in motion
    assert np.max(np.abs(recs[1].inputs["u"] - recs[0].inputs["u"])) < 1e-9 * np.max(np.abs(recs[0].inputs["u"]))
    out = sim.simulate(runner("SDOFBoucWen"), recs[1], {**TRUTH, "exc_type": 0})
    for k in ("y", "a"):
        scale = np.max(np.abs(recs[0].outputs[k]))
        assert np.max(np.abs(recs[1].outputs[k] - recs[0].outputs[k])) < 1e-9 * scale  # the files' 10 digits
    r0, r1 = (sim.residuals(out, rec) for rec in recs)  # per sample: (sim - meas) / RMS / sqrt(n)
    # the files' 10 digits of a value with a 5 mm (1 g) offset: about 3e-8 of the channel's RMS per sample
    assert np.max(np.abs(r1 - r0)) * np.sqrt(recs[0].n) < 1e-7
    measured("SDOF sweep with a 5 mm transducer zero and a 1 g accelerometer offset, simulated with the truth: "
             "NRMSE of y and a together", float(np.sqrt(np.sum(r1**2) / 2)), 2e-3)


@pytest.mark.parametrize("zero", [0.0, 5e-3])
def test_a_record_from_rest_is_told_from_a_segment_in_motion_whatever_the_sensor_zero(tmp_path, zero):
    """A 30 Hz response that builds up from rest (time constant 0.5 s) and a segment of the same motion cut in
    full swing, each read by a zeroed transducer and by one whose rest reading is 5 mm."""
    fs = 500.0
    t = np.arange(int(10 * fs)) / fs
    growing = 1e-4 * np.sin(2 * np.pi * 30 * t) * (1 - np.exp(-t / 0.5))
    swinging = 1e-4 * np.sin(2 * np.pi * 30 * t + 1.0)
    for name, y, at_rest in (("growing", growing, True), ("swinging", swinging, False)):
        path = write_measurement(tmp_path / f"{name}.csv", "SDOFBoucWen", t, {"F": (y * 1e5, "N", "u")},
                                 {"Y": (y + zero, "mm", "y")})
        assert sim.starts_at_rest(read_measurement(path)) is at_rest, name


def test_a_periodic_record_is_its_steady_period_repeated(tmp_path, runner, measured):
    """Three periods of a random-odd multisine through a Bouc-Wen loop of random shape, written by the CasADi
    reference: simulated as one steady period after the lead, repeated, the record matches the FMU run over
    every period at a tight tolerance, and the truth matches the reference's record."""
    from pyfit.analysis.excitation import PeriodicSignal, multisine
    from pyfit.analysis.signals import without_offset
    from pyfit.gap.effects import hysteresis_loop
    from pyfit.runtime.drive import drive

    truth = {**TRUTH, **hysteresis_loop(np.random.default_rng(2026))}
    fs, spp, periods, lead = 500.0, 2048, 3, 1
    signal = PeriodicSignal(multisine(spp, fs, 5.0, 80.0, 50.0, 5, odd=True), fs)
    t, y, u = simulate_truth(SyntheticSpec("SDOFBoucWen", signal, (lead + periods + 1) * spp / fs, fs, ["y"], truth,
                                           oversample=10, passband_ripple_db=0.005))
    keep = slice(lead * spp, (lead + periods) * spp)  # the reference's own transient dropped
    path = write_measurement(tmp_path / "ms.csv", "SDOFBoucWen", t[keep] - t[keep][0], {"F": (u["u"][keep], "N", "u")},
                             {"Y": (y["y"][keep], "m", "y")},
                             excitation={"kind": "multisine", "samples_per_period": spp, "periods": periods})
    rec = sim.record_of(read_measurement(path))
    assert rec.samples_per_period == spp and rec.n == periods * spp
    params = {**truth, "exc_type": 0}
    out = sim.simulate(runner("SDOFBoucWen"), rec, params, lead_periods=lead)
    every = without_offset(drive(runner("SDOFBoucWen"), rec.inputs, fs, ["y"], params, 4, spp, lead, 1e-10).values["y"])
    scale = np.sqrt(np.mean(rec.outputs["y"] ** 2))
    # the integrator's tolerance (sim.TOLERANCE, 1e-6 per step), a tenth of the lowest sensor noise of a record
    measured("periodic SDOF Bouc-Wen record: one steady period repeated against every period run at 1e-10, RMS "
             "difference / output RMS", np.sqrt(np.mean((out["y"] - every) ** 2)) / scale, 1e-4)
    # the 500 Hz input upsampled band-limited and the reference's sensor chain (0.005 dB anti-alias filter)
    measured("periodic SDOF Bouc-Wen record simulated with its truth against the CasADi reference: NRMSE",
             np.sqrt(np.mean((out["y"] - rec.outputs["y"]) ** 2)) / scale, 2e-3)


# a catalogue damper (masses 1.7 / 1.4 kg on 0.19 / 0.15 m arms, messenger EI 6.8 N·m²; a case of an earlier
# campaign draw) on which a model started from rest with its clamp displaced rang for a twentieth of the record
RINGING_DAMPER = {"m1": 1.705, "L1": 0.1861, "a1": 0.0483, "J_G1": 3.745e-3, "m2": 1.406, "L2": 0.1483, "a2": 0.0444,
                  "J_G2": 1.902e-3, "EI": 6.814}


@pytest.mark.parametrize("motion", ["a", "v"])
def test_a_damper_driven_by_an_integrated_clamp_motion_starts_at_rest_relative_to_its_clamp(tmp_path, runner, motion,
                                                                                          measured):
    """A catalogue damper shaken from rest by band-limited noise (2.3-15 Hz), the clamp recorded as acceleration
    (or velocity) only, cable-end displacement and acceleration recorded (CasADi reference, 2e-6 m sensor noise
    or its equivalent). The clamp displacement integrated from the record starts off rest by a few per cent of
    the motion (the integration constants): simulated with the truth, the model starts at rest relative to the
    clamp, so the first twentieth of the record fits as well as the rest (started from rest with the clamp
    displaced, acc_x1 misfit its first twentieth 24 times (a) and 18 times (v) as much as the rest)."""
    import dataclasses

    from pyfit.gap import datasets

    family = dataclasses.replace(datasets.DAMPER, band_hz=(2.34, 15.28))
    data = datasets.write_dataset(tmp_path, family, "none", seed=861115265, periods=2, base=RINGING_DAMPER,
                                  style=datasets.LabStyle("noise", ("x1", "acc_x1"), motion, record_s=6.0))
    # the highest level (0.2 mm RMS): its displacement noise stays within the test of a start from rest
    rec = sim.record_of(read_measurement(sorted(data.glob("*.csv"))[-1]), ("x_base", "v_base", "a_base"))
    assert rec.support == ("x_base", "v_base") and rec.first == 0
    out = sim.simulate(runner("StockbridgeDamper"), rec, {**datasets.DAMPER.linear, **RINGING_DAMPER, "exc_type": 0})
    e, y = out["acc_x1"] - rec.outputs["acc_x1"], rec.outputs["acc_x1"]
    parts = [np.sqrt(np.mean(p ** 2) / np.mean(y ** 2)) for p in np.array_split(e, 20)]
    # the sensor noise alone is the same in every twentieth: 1.5 leaves room for its scatter over 150 samples
    measured(f"damper from rest, clamp recorded as {motion} only, the truth simulated: acc_x1's NRMSE over the "
             "first twentieth of the record / the median twentieth's", parts[0] / np.median(parts), 1.5)
    measured(f"the same ({motion} only): acc_x1's NRMSE over the record", np.sqrt(np.mean(e ** 2) / np.mean(y ** 2)), 0.01)
    # the cable end's absolute displacement moves with the clamp: the rigid start motion is added back to it
    # (without that, 0.11 to 0.34); what is left is the integrated clamp displacement's own error (1-2 %)
    measured(f"the same ({motion} only): x1's NRMSE over the record", float(np.sqrt(np.mean((out["x1"] - rec.outputs["x1"]) ** 2)
                                                              / np.mean(rec.outputs["x1"] ** 2))), 0.03)


def test_a_parameter_set_the_integrator_crawls_through_fails_at_a_limit_set_by_the_nominal(tmp_path, runner,
                                                                                             monkeypatch):
    """A 4 s force sweep through the SDOF's linear resonance (35.6 Hz, 0.6 mm). A Bouc-Wen loop with
    β(γ + δ) = 1e10 m⁻¹ yields within 1e-10 m: its z equation has a rate near β(γ + δ)|ẋ| ≈ 1e9 s⁻¹, and the FMU's
    explicit Dormand-Prince steps stay below ~3/1e9 s, billions of steps for the record (hours). With the limit
    sim.with_time_limits sets from the linear model's own simulation (SLOW_FACTOR times its time, at least
    MIN_WALL_S) the run counts as failed within that limit instead of MAX_WALL_S; a strong loop that yields within
    1e-6 m is no such set and simulates. The limit is set from runs of the FMU, each made (a run the process
    remembers would time a look-up, and the limit fall to its floor whatever the record costs)."""
    from pyfit.runtime import drive

    real_driven, made = drive._driven, []
    monkeypatch.setattr(drive, "_driven", lambda *a, **k: made.append(1) or real_driven(*a, **k))
    fs = 500.0
    exc = Excitation(2, 50.0, 20.0, 50.0, 1.5)
    t, y, u = simulate_truth(SyntheticSpec("SDOFBoucWen", exc, 4.0, fs, ["y"], TRUTH, oversample=10,
                                           passband_ripple_db=0.005))
    path = write_measurement(tmp_path / "r.csv", "SDOFBoucWen", t, {"F": (u["u"], "N", "u")},
                             {"Y": (y["y"], "m", "y")})
    fmu = runner("SDOFBoucWen")
    rec = sim.record_of(read_measurement(path))
    assert rec.max_wall_s == sim.MAX_WALL_S
    limited, = sim.with_time_limits(fmu, [rec], {**TRUTH, "exc_type": 0}, repeats=3)
    assert len(made) == 3  # each timed run made, none returned from the process's memory
    assert sim.MIN_WALL_S <= limited.max_wall_s <= 0.1 * sim.MAX_WALL_S  # a 4 s record: well under a second
    loop = {**TRUTH, "exc_type": 0, "alpha": 5e4, "gamma": 0.5, "delta": 0.5, "nu": 1.0}
    assert sim.simulate(fmu, limited, {**loop, "beta": 1e6}) is not None
    t0 = time.perf_counter()
    assert sim.simulate(fmu, limited, {**loop, "beta": 1e10}) is None
    assert time.perf_counter() - t0 < 0.25 * sim.MAX_WALL_S  # cut by the record's limit, not the 60 s one


def test_a_softening_spring_pushed_past_its_peak_force_fails_where_it_escapes(runner):
    """m x'' + c x' + k x + k3 x³ = u with k3 < 0: the spring force peaks at x* = sqrt(k / (3|k3|)), F* = 2 k x* / 3.
    A force ramped to 0.8 F* and held is carried (the FMU follows scipy's Radau solution); one ramped to 1.2 F*
    is not: x runs off to infinity, and the FMU's run fails in the communication step where scipy's solution
    passes 100 x*, on the step-size rule (the step below a share of the communication step), not at the limit of
    the arithmetic far beyond."""
    import scipy.integrate

    p = {**TRUTH, "exc_type": 0, "k3": -1e11}
    x_star = np.sqrt(p["k"] / (3 * abs(p["k3"])))
    f_star = 2.0 * p["k"] * x_star / 3.0
    dt, stop = 1e-3, 1.5
    t = np.arange(int(round(stop / dt)) + 1) * dt
    ramp = np.minimum(t / 0.5, 1.0) ** 2 * (3 - 2 * np.minimum(t / 0.5, 1.0))  # smooth step over 0.5 s

    def escape(_, s):
        return abs(s[0]) - 100 * x_star
    escape.terminal = True

    for share, carried in ((0.8, True), (1.2, False)):
        force = share * f_star * ramp

        def rhs(tt, s):
            u = np.interp(tt, t, force)
            return [s[1], (u - p["c"] * s[1] - p["k"] * s[0] - p["k3"] * s[0] ** 3) / p["m"]]

        ref = scipy.integrate.solve_ivp(rhs, (0, stop), [0.0, 0.0], "Radau", t_eval=t, rtol=1e-10, atol=1e-14,
                                        events=escape, max_step=dt / 4)
        res = runner("SDOFBoucWen").simulate(stop, dt, ["y"], p, {"u": force}, t, tolerance=1e-8)
        if carried:
            assert ref.status == 0 and res.ok, res.message
            err = np.max(np.abs(res["y"] - ref.y[0])) / np.max(np.abs(ref.y[0]))
            assert err < 1e-7, err  # both integrate the same linear input at tolerances of 1e-8 and below
        else:
            t_escape = ref.t_events[0][0]
            assert not res.ok and "the step fell below 1e-08 of the communication step" in res.message, res.message
            t_fail = float(res.message.split("from t = ")[1].split(":")[0])
            assert t_fail <= t_escape < t_fail + dt, (t_fail, t_escape)
