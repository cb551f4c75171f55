"""Withheld-effect datasets: measurement files (theory §5) from a truth model that contains one effect
the nominal model lacks (or none: null cases), at three excitation levels.

No inverse crime: the truth is the CasADi reference integrated by CVODES (TRUTH_RTOL) at 10x the sensor
rate, with the excitation as a continuous sum of sines, seen through a sensor chain (zero-phase FIR
anti-alias filter and decimation) with noise; the diagnosis fits the FMU (another implementation, another
integrator) at the sensor rate. The excitation is a random-odd multisine (odd lines only, one in four
left out as detection lines): a force on the SDOF mass, or the clamp motion of the damper (displacement,
velocity and acceleration recorded, as a shaker controller does). The leading (transient) periods and one
trailing period (filter edge) are dropped, so each file holds steady-state periods.
"""
from __future__ import annotations

import dataclasses
import hashlib
import json
import pathlib
import pickle
import tempfile
from dataclasses import dataclass

import numpy as np

from pyfit.io.data import write_measurement
from pyfit.io.impedance import write_impedance
from pyfit.analysis.excitation import (Excitation, PeriodicSignal, SteppedSine, band_noise,
                                       motion_with_derivatives, multisine)
from pyfit.reference.synthetic import UNITS, SyntheticSpec, simulate_truth
from pyfit.gap.effects import BUILTINS, tangent


@dataclass(frozen=True)
class Family:
    """How the test cases of one system are made (SI units)."""

    model: str  # reference model / FMU name
    linear: dict  # truth without any effect (the nominal model's structure)
    withheld: dict  # effect -> truth parameters added to `linear`
    tangent: dict  # parameters that switch every effect off (Bouc-Wen kept as its tangent stiffness)
    levels: tuple  # RMS of the excitation (N or m)
    level_unit: str
    band_hz: tuple
    fs: float
    samples_per_period: int
    lead_periods: int  # transient periods simulated and dropped
    outputs: tuple
    noise: float  # sensor noise standard deviation [m]


def _withheld(family: str) -> dict:
    """Each built-in effect's reference truth (pyfit.gap.effects), and 'none' (a null case)."""
    return {**{n: b.truth for n, b in BUILTINS[family].items() if b.truth}, "none": {}}


SDOF = Family(
    "SDOFBoucWen", {"m": 2.0, "c": 10.0, "k": 1e5, "alpha": 0.0},  # f0 = 35.6 Hz, zeta = 1.1 %
    _withheld("sdof"), tangent("sdof"), (10.0, 25.0, 50.0), "N", (5.0, 80.0), 500.0, 2048, 1, ("y",), 5e-6)

DAMPER = Family(
    "StockbridgeDamper", tangent("damper"),  # the linear FE damper of theory §1.3, its eccentric masses included
    _withheld("damper"), tangent("damper"), (0.05e-3, 0.1e-3, 0.2e-3), "mm", (5.0, 40.0), 500.0, 2048, 2,
    ("x1", "x2"), 2e-6)

FAMILIES = {"sdof": SDOF, "damper": DAMPER}
PERIODS = 3
EXCITATIONS = ("multisine", "sweep", "stepped_sine", "noise")  # of write_dataset (LabStyle.excitation)
# a campaign's damper cases draw their excitation from these (pyfit.gap.campaign); write_dataset also writes a clamp's
# stepped sine, whose frequency glides to each step's over GLIDE_S at a constant velocity amplitude
CLAMP_EXCITATIONS = ("multisine", "sweep", "noise")
STEPS = 16  # frequencies of a stepped sine
GLIDE_S = 0.2  # [s] a clamp's stepped sine moves to the next frequency over this (its motion stays continuous)
# CVODES tolerances of the truth: against 1e-10 / 1e-14 the SDOF records change by at most 1.5e-6 of the
# output's standard deviation, far below the sensor noise (1e-3 of it and more), in a third less time
TRUTH_RTOL, TRUTH_ATOL = 1e-8, 1e-12
OVERSAMPLE = 10  # the truth's rate over the sensor rate (its sensor chain decimates by this)


SWEEP_LEVELS = {"SDOFBoucWen": ((10.0, 25.0, 50.0), "N"),  # force amplitude
                "StockbridgeDamper": ((0.005, 0.01, 0.02), "m/s")}  # clamp velocity amplitude
# a damper characteristic test (IEC 61897): frequencies [Hz] through both resonances of the design damper,
# at the sweep levels; noise 0.5 % in |Z| and 0.3 deg in phase (RMS of |Z_meas/Z_true - 1| about 0.0073),
# stated in the sidecar as an uncertainty of 1 %
IMPEDANCE_FREQUENCIES_HZ = (8.0, 10.0, 13.0, 17.0, 22.0, 30.0, 40.0)
IMPEDANCE_NOISE = (0.005, float(np.radians(0.3)))
IMPEDANCE_UNCERTAINTY = 0.01


@dataclass(frozen=True)
class LabStyle:
    """How a test bench would have recorded a case: the excitation ('multisine': steady-state periods;
    'sweep': a linear sweep over the family's band from rest, record_s long, constant force amplitude for the
    SDOF and constant clamp-velocity amplitude for the damper; 'stepped_sine': STEPS log-spaced frequencies
    over the band, record_s / STEPS each, at the sweep's amplitudes (the damper's clamp: its frequency gliding
    to each step's over GLIDE_S, so that its displacement, velocity and acceleration stay continuous);
    'noise': band-limited random noise over the band from rest, record_s long, at the
    multisine's RMS levels; 'impedance': the damper's characteristic
    test, see write_impedance_case), the outputs recorded (None: the family's
    displacements; e.g. ("a",) or ("acc_x1", "acc_x2") for accelerometers) and which of the clamp's x, v,
    a were recorded (the damper's shaker controller gives all three; an accelerometer only 'a')."""

    excitation: str = "multisine"
    outputs: tuple | None = None
    motion: str = "xva"
    record_s: float = 35.0  # length of a sweep, stepped-sine or noise record [s]

    def __post_init__(self):  # a multisine's length is its periods'
        stepped = self.excitation == "stepped_sine"
        shortest, why = ((STEPS * GLIDE_S, f"each of its {STEPS} dwells longer than a clamp's {GLIDE_S:g} s glide")
                         if stepped else (1.0, "a sweep's ramp alone takes 1 s"))
        if self.excitation != "multisine" and not self.record_s > shortest:
            raise ValueError(f"record length (record_s, --record-s) {self.record_s:g} s: a {self.excitation} record "
                             f"must be longer than {shortest:g} s ({why})")


def excitations(family: Family) -> tuple[str, ...]:
    """The excitations write_dataset records `family` under: the SDOF's EXCITATIONS; a damper's clamp excitations
    and its stepped sine (a campaign draws that one only when asked for: its glides need longer records)."""
    return EXCITATIONS if family.model == "SDOFBoucWen" else CLAMP_EXCITATIONS + ("stepped_sine",)


def _truth_params(family: Family, effect: str, base: dict, truth: dict | None = None) -> dict:
    """Truth = linear + base (a described system) + the effect(s) ('a+b': several), or + `truth` when given
    (e.g. parameters drawn at random across the family); an effect value may be a function of the system's
    parameters (a deviation from them, e.g. mass offsets)."""
    from pyfit.reference.models import by_name

    system = {**by_name(family.model).defaults, **family.linear, **base}
    if truth is None:
        truth = {k: v for name in effect.split("+") for k, v in family.withheld[name].items()}
    extra = {k: (v(system) if callable(v) else v) for k, v in truth.items()}
    return {**family.linear, **base, **extra}


TRUTHS_KEPT = 16  # the different truths last used that a process keeps (pyfit.gap.datasets._truth)
_truths: dict[str, tuple] = {}


def _truth(spec: SyntheticSpec) -> tuple:
    """simulate_truth(spec), reused while it is among the TRUTHS_KEPT different ones this process used last: a
    case's sizing writes its records several times (pyfit.gap.sizing), and a damper effect's tangent truth (the
    effect off) is the same whatever its strength. The same model parameters, signal, record and sensor chain give
    the same simulation, so a reused result is the one simulating again would give."""
    from pyfit.reference.models import by_name

    key = hashlib.sha256(pickle.dumps((spec.model, by_name(spec.model).param_vector(spec.params), spec.excitation,
                                       spec.stop_time, spec.sample_rate_hz, spec.outputs, spec.noise_std,
                                       spec.oversample, spec.seed, spec.solver, spec.anti_alias,
                                       spec.passband_ripple_db, spec.rtol, spec.atol))).hexdigest()
    result = _truths.pop(key, None) or simulate_truth(spec)
    _truths[key] = result  # the last used last
    while len(_truths) > TRUTHS_KEPT:
        _truths.pop(next(iter(_truths)))
    return result


def _same_system(model: str, a: dict, b: dict) -> bool:
    """Whether two parameter sets give the reference model the same parameter vector (the same simulation: a
    null truth is its own tangent truth)."""
    from pyfit.reference.models import by_name

    ref = by_name(model)
    return bool(np.array_equal(ref.param_vector(a), ref.param_vector(b)))


def _level_signal(kind: str, family: Family, level: float, style: LabStyle, seed: int, periods: int):
    """One level's excitation, the seconds simulated and the samples kept: a sweep, a stepped sine or band-limited
    noise from rest over style.record_s, or `periods` periods of a random-odd multisine after the lead periods."""
    (f0, f1), fs, spp = family.band_hz, family.fs, family.samples_per_period
    stop, keep = style.record_s, slice(0, int(round(style.record_s * fs)))
    if kind == "sweep":
        signal = Excitation(2 if family.model == "SDOFBoucWen" else 4, level, f0, f1,
                            (f1 - f0) / (style.record_s - 1.0), t_ramp=1.0)
    elif kind == "stepped_sine":
        clamp = dict(glide_s=GLIDE_S, velocity=True) if family.model != "SDOFBoucWen" else {}
        signal = SteppedSine(tuple(np.geomspace(f0, f1, STEPS)), style.record_s / STEPS, level, **clamp)
    elif kind == "noise":
        signal = band_noise(f0, f1, level, seed)
    else:
        lead = family.lead_periods
        signal = PeriodicSignal(multisine(spp, fs, f0, f1, level, seed, odd=True), fs)
        stop, keep = (lead + periods + 1) * spp / fs, slice(lead * spp, (lead + periods) * spp)
    return signal, stop, keep


def _recorded_inputs(family: Family, kind: str, signal, t_in, motion: str) -> dict:
    """The input channels as recorded at the times `t_in`: the SDOF's force, else the clamp's x, v, a of `motion`."""
    if family.model == "SDOFBoucWen":
        return {"u_meas": (signal(t_in), "N", "u")}
    values = ({"x": signal(t_in), "v": signal.derivative(t_in, 1), "a": signal.derivative(t_in, 2)}
              if kind == "multisine" else motion_with_derivatives(signal, t_in, ("x", "v", "a")))
    return {f"{var}_meas": (values[k], u, var) for k, u, var in
            (("x", "m", "x_base"), ("v", "m/s", "v_base"), ("a", "m/s2", "a_base")) if k in motion}


def _change(exact: dict, clean: dict, keep: slice, recorded) -> dict:
    """What an effect changes of a level's outputs against the truth without it: the RMS (RMS(y)/RMS(y_tangent) -
    1) and the output itself (RMS(y - y_tangent)/RMS(y_tangent)), over every recorded output."""
    num = sum(np.mean((exact[o][keep] - clean[o][keep]) ** 2) for o in recorded)
    den = sum(np.mean(clean[o][keep] ** 2) for o in recorded)
    rms = sum(np.mean(exact[o][keep] ** 2) for o in recorded)
    return {"rms": float(np.sqrt(rms / den) - 1.0), "output": float(np.sqrt(num / den))}


def _check_request(family: Family, effect: str, style: LabStyle, truth: dict | None) -> None:
    if truth is None and any(e not in family.withheld for e in effect.split("+")):
        raise ValueError(f"effect '{effect}' unknown for {family.model}; allowed: {', '.join(family.withheld)} "
                         "(or several joined by '+', or the truth's parameters given)")
    allowed = excitations(family)
    if style.excitation not in allowed:
        raise ValueError(f"excitation '{style.excitation}' unknown for {family.model}; allowed: "
                         f"{', '.join(allowed)}")


def write_dataset(out_dir, family: Family, effect: str, seed: int = 0, periods: int = PERIODS,
                  style: LabStyle = LabStyle(), base: dict | None = None, truth: dict | None = None) -> pathlib.Path:
    """Write one dataset (a file per level) whose truth has `effect` ('none' for a null case), as recorded in
    `style`, of the system `base` (FMU parameter overrides, e.g. a described damper; None: the defaults);
    truth.json beside it records the truth and what the effect changes at each level against the truth
    without it (Bouc-Wen as its tangent stiffness): the output RMS (RMS(y)/RMS(y_tangent) - 1) and the
    output itself (RMS(y - y_tangent)/RMS(y_tangent)); and each effect's size against the noise
    (member_to_noise: the RMS of the truth less the truth with that effect off, over the RMS of the sensor
    noise, the squares averaged over every level and output: how far the data show it beside the others, before
    any model takes up part of it; only the effects `family.tangent` switches off, not a channel delay or a mass
    offset); the diagnosis never reads it."""
    _check_request(family, effect, style, truth)
    out = pathlib.Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    truth = _truth_params(family, effect, base or {}, truth)
    recorded = tuple(style.outputs or family.outputs)
    rng = np.random.default_rng(seed)
    changes = {}
    members = {e: {k: v for k, v in family.tangent.items() if k in family.withheld.get(e, {})}
               for e in effect.split("+") if e != "none"}
    member_sq, channels = {e: 0.0 for e, off in members.items() if off}, 0  # of the records' outputs
    kind = style.excitation
    amplitude = kind in ("sweep", "stepped_sine")  # levels are amplitudes (else RMS values)
    levels, unit = SWEEP_LEVELS[family.model] if amplitude else (family.levels, family.level_unit)
    physical = {k: v for k, v in truth.items() if k != "sensor_delay"}  # the delay is in the recording

    def simulated(signal, stop, params):
        return _recorded_truth(family, signal, stop, recorded, params)

    for i, level in enumerate(levels):
        signal, stop, keep = _level_signal(kind, family, level, style, seed, periods)
        t, exact, _ = simulated(signal, stop, physical)
        tangent = {**physical, **family.tangent}
        clean = exact if _same_system(family.model, tangent, physical) else simulated(signal, stop, tangent)[1]
        tk = t[keep] - t[keep][0]
        sigma = {o: _noise_of(family, o, clean[o][keep]) for o in recorded}
        channels += len(recorded)
        for e in member_sq:  # the truth with this member off, the others on (one member: the tangent truth)
            off = clean if len(members) == 1 else simulated(signal, stop, {**physical, **members[e]})[1]
            member_sq[e] += sum(np.mean((exact[o][keep] - off[o][keep]) ** 2) / sigma[o] ** 2 for o in recorded)
        changes[f"{level:g}"] = _change(exact, clean, keep, recorded)
        # a skew between the channels: the input channel records the signal `sensor_delay` seconds early
        inputs = _recorded_inputs(family, kind, signal, t[keep] + truth.get("sensor_delay", 0.0), style.motion)
        outputs = {f"{o}_meas": (exact[o][keep] + rng.normal(0.0, sigma[o], len(tk)),
                                 UNITS.get(o, "m"), o) for o in recorded}
        shown = level * 1e3 if unit == "mm" else level
        write_measurement(out / f"level{i + 1}_{shown:g}{unit.replace('/', '')}.csv", family.model, tk, inputs,
                          outputs, level=f"{'amplitude' if amplitude else 'RMS'} {shown:g} {unit}", level_value=shown,
                          excitation=_excitation_meta(kind, signal, family, level, family.samples_per_period,
                                                      periods),
                          notes=f"synthetic: CasADi reference (cvodes) at 10x the sensor rate, zero-phase FIR "
                                f"anti-alias + decimation, noise {family.noise} m (or its equivalent), seed {seed}")
    (out / "truth.json").write_text(json.dumps({"effect": effect, "params": truth, "seed": seed,
                                                "style": style.__dict__, "rms_change": changes,
                                                "member_to_noise": {e: float(np.sqrt(v / channels))
                                                                    for e, v in member_sq.items()}}, indent=1))
    return out


def _recorded_truth(family: Family, signal, stop: float, recorded, params: dict) -> tuple:
    """The truth `params` driven by `signal` for `stop` s through the family's sensor chain: (t, outputs, ...)."""
    return _truth(SyntheticSpec(family.model, signal, stop, family.fs, list(recorded), params,
                                oversample=OVERSAMPLE, rtol=TRUTH_RTOL, atol=TRUTH_ATOL))


def write_test(data_dir, family: Family, signal, stop_s: float, kind: str, level: float, name: str,
               seed: int) -> pathlib.Path:
    """One more record of the case write_dataset wrote into `data_dir` (its truth.json: the truth and how it was
    recorded): the same truth driven by `signal` (a force [N] or a clamp motion [m]) from rest for `stop_s` s,
    through the same sensor chain (outputs, anti-alias filter and decimation, channel skew; noise drawn with
    `seed`), written as `name`.csv with its sidecar; `kind` ('sweep' or 'stepped_sine') and the amplitude `level`
    [N, or m/s for a clamp] are the sidecar's excitation. E.g. the test a report proposes (pyfit.gap.proposal)."""
    out = pathlib.Path(data_dir)
    meta = json.loads((out / "truth.json").read_text())
    truth, style = meta["params"], meta["style"]
    recorded = tuple(style["outputs"] or family.outputs)
    physical = {k: v for k, v in truth.items() if k != "sensor_delay"}

    t, exact, _ = _recorded_truth(family, signal, stop_s, recorded, physical)
    keep = slice(0, int(round(stop_s * family.fs)))
    # the noise of a non-displacement output follows the truth without its effects, as in write_dataset
    clean = _recorded_truth(family, signal, stop_s, recorded, {**physical, **family.tangent})[1]
    tk, rng = t[keep] - t[keep][0], np.random.default_rng(seed)
    inputs = _recorded_inputs(family, kind, signal, t[keep] + truth.get("sensor_delay", 0.0), style["motion"])
    outputs = {f"{o}_meas": (exact[o][keep] + rng.normal(0.0, _noise_of(family, o, clean[o][keep]), len(tk)),
                             UNITS.get(o, "m"), o) for o in recorded}
    unit = "m/s" if family.model != "SDOFBoucWen" else "N"
    path = out / f"{name}.csv"
    write_measurement(path, family.model, tk, inputs, outputs, level=f"amplitude {level:g} {unit}", level_value=level,
                      excitation=_excitation_meta(kind, signal, dataclasses.replace(
                          family, band_hz=_band_of(signal)), level, family.samples_per_period, 0),
                      notes=f"synthetic: the case's truth on a further test (CasADi reference, the same sensor "
                            f"chain), noise seed {seed}")
    return path


def _band_of(signal) -> tuple:
    """The frequency range [Hz] a sweep or stepped sine covers."""
    if isinstance(signal, SteppedSine):
        return min(signal.frequencies), max(signal.frequencies)
    return signal.f_start, signal.f_end


def effect_sizes(family: Family, effect: str, seed: int = 0, periods: int = PERIODS, style: LabStyle = LabStyle(),
                 base: dict | None = None, truth: dict | None = None) -> dict[str, float]:
    """Each withheld effect's size over the sensor noise (write_dataset's `member_to_noise`) on the records
    write_dataset would write with these arguments, written to a scratch folder that is removed after."""
    with tempfile.TemporaryDirectory() as scratch:
        written = write_dataset(scratch, family, effect, seed, periods, style, base, truth)
        return json.loads((written / "truth.json").read_text())["member_to_noise"]


def _excitation_meta(kind: str, signal, family: Family, level: float, spp: int, periods: int) -> dict:
    """The sidecar's [excitation] table of a record written by write_dataset (frequencies in Hz)."""
    f0, f1 = family.band_hz
    if kind == "sweep":
        return {"kind": "linear_sweep", "f_start": f0, "f_end": f1, "amplitude": level}
    if kind == "stepped_sine":
        glide = {"glide_s": signal.glide_s} if signal.glide_s else {}
        return {"kind": "stepped_sine", "frequencies": list(signal.frequencies), "dwell_s": signal.dwell_s,
                "amplitude": level, **glide}
    if kind == "noise":
        return {"kind": "random", "f_min": f0, "f_max": f1, "rms": level}
    return {"kind": "multisine", "samples_per_period": spp, "periods": periods, "f_min": f0, "f_max": f1,
            "rms": level, "odd": True}


def write_impedance_case(out_dir, effect: str, seed: int = 0, base: dict | None = None) -> pathlib.Path:
    """One withheld-effect case of the damper as a characteristic test (IEC 61897): the CasADi reference
    damper's clamp impedance at IMPEDANCE_FREQUENCIES_HZ and the sweep levels (clamp velocity amplitudes
    [m/s]), with IMPEDANCE_NOISE, in OUT/impedance_test.csv (+ sidecar stating IMPEDANCE_UNCERTAINTY);
    truth.json beside it (never read by the diagnosis)."""
    from pyfit.reference.impedance import reference_impedance

    if effect not in DAMPER.withheld:
        raise ValueError(f"effect '{effect}' unknown for {DAMPER.model}; allowed: {', '.join(DAMPER.withheld)}")
    out = pathlib.Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    truth = _truth_params(DAMPER, effect, base or {})
    amps, z = reference_impedance(IMPEDANCE_FREQUENCIES_HZ, SWEEP_LEVELS[DAMPER.model][0], truth,
                                  noise=IMPEDANCE_NOISE, seed=seed)
    write_impedance(out / "impedance_test.csv", IMPEDANCE_FREQUENCIES_HZ, amps, z,
                    f"synthetic: CasADi reference damper (cvodes), noise {IMPEDANCE_NOISE[0]:g} relative in |Z|, "
                    f"{np.degrees(IMPEDANCE_NOISE[1]):g} deg in phase, seed {seed}", IMPEDANCE_UNCERTAINTY)
    (out / "truth.json").write_text(json.dumps({"effect": effect, "params": truth, "seed": seed,
                                                "style": {"excitation": "impedance"}}, indent=1))
    return out


def _noise_of(family: Family, output: str, clean: np.ndarray) -> float:
    """Sensor noise [SI] of a channel: the family's displacement noise, or for another quantity the same
    fraction of its RMS as the displacement noise is of a displacement channel's RMS (about 0.3-1 %)."""
    if UNITS.get(output, "m") == "m":
        return family.noise
    return 0.005 * float(np.sqrt(np.mean(clean**2)))


def write_cases(out_dir, family: str = "sdof", null_seeds=(0, 1, 2), periods: int = PERIODS,
                style: LabStyle = LabStyle(), base: dict | None = None) -> list[pathlib.Path]:
    """The test cases of a family: each effect withheld (seed 0) and the null case for every noise seed."""
    fam, out = FAMILIES[family], pathlib.Path(out_dir)
    if style.excitation == "impedance":
        if family != "damper":
            raise ValueError(f"excitation 'impedance' is a damper test; the family is '{family}'")
        return ([write_impedance_case(out / f"damper_{e}", e, base=base) for e in fam.withheld
                 if e not in ("none", "sensor_delay")]  # an impedance table has no channels to skew
                + [write_impedance_case(out / f"damper_none_seed{s}", "none", s, base) for s in null_seeds])
    paths = [write_dataset(out / f"{family}_{e}", fam, e, periods=periods, style=style, base=base)
             for e in fam.withheld if e != "none"]
    return paths + [write_dataset(out / f"{family}_none_seed{s}", fam, "none", seed=s, periods=periods, style=style,
                                  base=base) for s in null_seeds]
