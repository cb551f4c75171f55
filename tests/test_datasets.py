"""Withheld-effect datasets (pyfit.gap.datasets) with a stepped sine and band-limited noise: what the files
hold against the signal they were made from (a damper's clamp stepped sine: continuous motion at a constant
velocity amplitude), and a constant-velocity stepped sine refused without a glide (its displacement would jump)."""
import json

import numpy as np
import pytest

from pyfit.analysis.excitation import SteppedSine, band_noise, motion_with_derivatives
from pyfit.gap import datasets
from pyfit.io.data import read_measurement


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    root = tmp_path_factory.mktemp("lab")
    return {kind: datasets.write_dataset(root / kind, datasets.SDOF, "none", seed=3,
                                         style=datasets.LabStyle(kind, record_s=6.0))
            for kind in ("stepped_sine", "noise")}


def test_a_stepped_sine_file_holds_the_controller_signal_and_its_steps(written):
    first = read_measurement(sorted(written["stepped_sine"].glob("level1_*.csv"))[0])
    steps = first.excitation["frequencies"]
    assert first.excitation["kind"] == "stepped_sine" and len(steps) == datasets.STEPS
    assert steps[0] == pytest.approx(datasets.SDOF.band_hz[0]) and steps[-1] == pytest.approx(datasets.SDOF.band_hz[1])
    signal = SteppedSine(tuple(steps), first.excitation["dwell_s"], first.excitation["amplitude"])
    u = first.by_variable("inputs")["u"]
    assert first.t[-1] == pytest.approx(6.0, abs=2 / datasets.SDOF.fs)
    assert np.max(np.abs(u - signal(first.t))) < 1e-9 * first.excitation["amplitude"]  # the file's rounding


def test_a_noise_file_holds_band_limited_noise_at_its_level(written):
    for path in sorted(written["noise"].glob("*.csv")):
        m = read_measurement(path)
        assert m.excitation["kind"] == "random"
        u = m.by_variable("inputs")["u"]
        assert np.max(np.abs(u - band_noise(m.excitation["f_min"], m.excitation["f_max"], m.excitation["rms"],
                                            seed=3)(m.t))) < 1e-9 * m.excitation["rms"]
        # the RMS of 5 s of 150 incommensurate sines scatters about the level by a few %
        assert np.sqrt(np.mean(u[m.t > 1.0] ** 2)) == pytest.approx(m.excitation["rms"], rel=0.15)


def test_a_clamp_stepped_sine_holds_each_velocity_amplitude_and_moves_the_clamp_continuously(tmp_path):
    """The damper's clamp under a stepped sine (8 s, 16 steps of 0.5 s, each frequency reached over a 0.2 s glide):
    the recorded displacement, velocity and acceleration are the controller's motion and its exact derivatives; in
    the last 0.2 s of each step the velocity amplitude is the level; and between any two samples the displacement
    and the velocity change by the trapezoid of their derivatives within the trapezoid rule's error for the highest
    frequency, (omega dt)^2 / 12 of a sample's change (a jump at a step would exceed it)."""
    data = datasets.write_dataset(tmp_path, datasets.DAMPER, "none", style=datasets.LabStyle("stepped_sine",
                                                                                             record_s=8.0))
    m = read_measurement(sorted(data.glob("level3_*.csv"))[0])
    steps, dwell, level = m.excitation["frequencies"], m.excitation["dwell_s"], m.excitation["amplitude"]
    assert m.excitation["glide_s"] == datasets.GLIDE_S and len(steps) == datasets.STEPS and dwell == 0.5
    signal = SteppedSine(tuple(steps), dwell, level, glide_s=datasets.GLIDE_S, velocity=True)
    motion = m.by_variable("inputs")
    exact = motion_with_derivatives(signal, m.t, ("x_base", "v_base", "a_base"))
    for name, values in exact.items():
        assert np.max(np.abs(motion[name] - values)) < 1e-8 * np.max(np.abs(values)), name
    for j in range(1, len(steps)):  # after the input's ramp and each glide
        late = (m.t > (j + 1) * dwell - 0.2) & (m.t < (j + 1) * dwell)
        # the largest sample of a sine lies within 1 - cos(pi f / fs) of its amplitude
        assert np.max(np.abs(motion["v_base"][late])) == pytest.approx(
            level, rel=1 - np.cos(np.pi * steps[j] / m.sample_rate_hz) + 1e-6)
    dt = 1 / m.sample_rate_hz
    bound = (2 * np.pi * steps[-1] * dt) ** 2 / 12  # measured 0.99 of it: the glides add 1.1 at most
    for low, high in (("x_base", "v_base"), ("v_base", "a_base")):
        rest = np.diff(motion[low]) - dt * (motion[high][1:] + motion[high][:-1]) / 2
        assert np.max(np.abs(rest)) <= 1.1 * bound * dt * np.max(np.abs(motion[high])), low


def test_a_constant_velocity_stepped_sine_needs_a_glide():
    with pytest.raises(ValueError, match="velocity = True needs glide_s > 0"):
        SteppedSine((5.0, 10.0), 1.0, 0.01, velocity=True)


def _size(tmp_path, effect: str, truth: dict) -> dict:
    style = datasets.LabStyle("noise", record_s=2.0)
    folder = tmp_path / effect / "_".join(f"{k}{v:g}" for k, v in truth.items())
    path = datasets.write_dataset(folder, datasets.SDOF, effect, seed=5, style=style, truth=truth)
    return json.loads((path / "truth.json").read_text())["member_to_noise"]


def test_each_withheld_effect_is_sized_against_the_noise(tmp_path):
    """A weak quadratic damper (c2 = 0.02 N·s²/m², a five-hundredth of the family's reference) changes the
    response in proportion to c2 (first order), and beside a weak cubic spring by what it changes alone (their
    cross term is second order); an effect at zero strength changes nothing."""
    weak, twice = _size(tmp_path, "quadratic_damping", {"c2": 0.02}), _size(tmp_path, "quadratic_damping",
                                                                             {"c2": 0.04})
    assert twice["quadratic_damping"] / weak["quadratic_damping"] == pytest.approx(2.0, rel=0.03)
    pair = _size(tmp_path, "cubic_stiffness+quadratic_damping", {"k3": 3e6, "c2": 0.02})
    assert pair["quadratic_damping"] == pytest.approx(weak["quadratic_damping"], rel=0.05)
    assert _size(tmp_path, "cubic_stiffness+quadratic_damping", {"k3": 3e6, "c2": 0.0})["quadratic_damping"] == 0.0
    assert _size(tmp_path, "none", {}) == {}


def test_a_further_test_on_a_case_s_truth_holds_its_steady_state_response(tmp_path):
    """datasets.write_test (the follow-up of a campaign case): a stepped sine recorded on a linear SDOF case's truth
    through the same sensor chain; each dwell's steady-state displacement amplitude equals the closed form
    F / sqrt((k - m ω²)² + (c ω)²) of the truth's m, c, k within 1 % (the sensor noise's share of the fitted
    amplitude is a few 1e-3; the transient has decayed below 1e-3 after 2 s at ζ = 1.1 %)."""
    family = datasets.SDOF
    data = datasets.write_dataset(tmp_path / "data", family, "none", style=datasets.LabStyle("sweep", record_s=3.0))
    signal = SteppedSine((18.0, 31.0, 47.0), 3.0, 12.0)
    path = datasets.write_test(data, family, signal, 9.0, "stepped_sine", 12.0, "further_test", seed=5)
    m = read_measurement(path)
    assert m.level_value == 12.0 and path.with_suffix(".toml").is_file()
    y, fs, lin = m.values["y_meas"], family.fs, family.linear
    for i, f in enumerate(signal.frequencies):
        steady = y[int((3 * i + 2.0) * fs):int(3 * (i + 1) * fs)]
        t = np.arange(len(steady)) / fs
        basis = np.column_stack([np.sin(2 * np.pi * f * t), np.cos(2 * np.pi * f * t), np.ones_like(t)])
        a, b, _ = np.linalg.lstsq(basis, steady, rcond=None)[0]
        w = 2 * np.pi * f
        assert np.hypot(a, b) == pytest.approx(12.0 / np.hypot(lin["k"] - lin["m"] * w * w, lin["c"] * w), rel=0.01)
