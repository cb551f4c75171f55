"""The compiled co-simulation loop (pyfit/runtime/cs_driver.c) gives the same numbers as the Python loop it
replaces, bit for bit, with linear, quadratic (slopes and curvatures sent) and held inputs, and reports a
diverging run the same way."""
import numpy as np
import pytest

import pyfit.runtime.fmu as fmu_module
from pyfit.runtime.native import cs_loop


@pytest.fixture()
def inputs():
    rng = np.random.default_rng(0)
    t = np.arange(1501) / 750.0
    return t, {"u": 20.0 * rng.standard_normal(len(t))}


def _both(runner, monkeypatch, **kwargs):
    compiled = runner.simulate(**kwargs)
    with monkeypatch.context() as m:
        m.setattr(fmu_module, "cs_loop", lambda: None)
        python = runner.simulate(**kwargs)
    return compiled, python


def test_compiled_loop_is_available_here():
    assert cs_loop() is not None  # the machine that runs the tests has the C compiler the FMU build needs


@pytest.mark.parametrize("drive", ["lines", "held", "quadratic"])
def test_compiled_and_python_loops_agree_bit_for_bit(runner, inputs, monkeypatch, drive):
    from pyfit.analysis.signals import step_quadratics

    t, u = inputs
    fmu = runner("SDOFBoucWen")
    derivatives = None
    if drive == "quadratic":
        slope, curvature = step_quadratics(u["u"], 1 / 750.0)
        derivatives = ({"u": slope}, {"u": curvature})
    compiled, python = _both(fmu, monkeypatch, stop_time=t[-1], output_interval=1 / 750.0, outputs=["y", "z"],
                             params={"exc_type": 0}, inputs=u, input_time=t, hold_inputs=drive == "held",
                             input_derivatives=derivatives)
    assert compiled.ok and python.ok
    for o in ("y", "z"):
        assert np.array_equal(compiled[o], python[o])
    if drive == "quadratic":  # the curvatures reach the FMU: another input than the lines between samples
        lines = fmu.simulate(t[-1], 1 / 750.0, ["y"], {"exc_type": 0}, inputs=u, input_time=t)
        assert not np.array_equal(lines["y"], compiled["y"])


def test_a_diverging_run_fails_the_same_way_in_both_loops(runner, inputs, monkeypatch):
    t, u = inputs
    fmu = runner("SDOFBoucWen")
    compiled, python = _both(fmu, monkeypatch, stop_time=t[-1], output_interval=1 / 750.0, outputs=["y"],
                             params={"exc_type": 0, "k": -1e9, "alpha": 0.0}, inputs=u, input_time=t)
    assert not compiled.ok and not python.ok
    assert "diverged" in compiled.message or "integration failed" in compiled.message
    assert np.all(np.isnan(compiled["y"]))
    assert fmu.simulate(t[-1], 1 / 750.0, ["y"], {"exc_type": 0}, inputs=u, input_time=t).ok  # usable again


def test_a_run_past_its_wall_clock_limit_fails_the_same_way_in_both_loops(runner, inputs, monkeypatch):
    """1500 communication points cannot be done within 1 µs: both loops stop at a check (every 16 points) with
    the limit in the message, and the instance is usable again."""
    t, u = inputs
    fmu = runner("SDOFBoucWen")
    compiled, python = _both(fmu, monkeypatch, stop_time=t[-1], output_interval=1 / 750.0, outputs=["y"],
                             params={"exc_type": 0}, inputs=u, input_time=t, max_wall_s=1e-6)
    for res in (compiled, python):
        assert not res.ok and "longer than its limit of 1e-06 s" in res.message, res.message
    assert fmu.simulate(t[-1], 1 / 750.0, ["y"], {"exc_type": 0}, inputs=u, input_time=t, max_wall_s=60.0).ok
