"""Conductor span FMU and the span + damper co-simulation: analytic decay, energy balance, damper at a node."""
import numpy as np
import pytest

from pyfit.runtime.cosim import cosimulate
from pyfit.design.span import mode_decay

C = np.sqrt(28000.0 / 1.628)  # m/s, wave speed of the default span (T = 28 kN, m_l = 1.628 kg/m)


def test_span_mode_decays_at_its_analytic_frequency_and_damping(runner):
    n, zeta = 5, 0.002
    f = n * C / (2 * 30.0)
    stop = 0.0001 * round(2.0 / 0.0001)
    r = cosimulate({"span": runner("ConductorSpan")}, [], stop, 1e-4, ["span.E", "span.q[5]"],
                   {"span": {"exc_type": 0, "q[5]": 5e-3, "m_c": 0.0}})  # bare span
    t = r.time
    # energy of a viscously damped mode: E0 exp(-2 zeta w t) (to first order in zeta)
    rate = -np.polyfit(t, np.log(r["span.E"]), 1)[0]
    assert rate == pytest.approx(2 * zeta * 2 * np.pi * f, rel=0.01)
    crossings = np.nonzero(np.diff(np.sign(r["span.q[5]"])) != 0)[0]
    f_measured = (len(crossings) - 1) / 2 / (t[crossings[-1]] - t[crossings[0]])
    assert f_measured == pytest.approx(f * np.sqrt(1 - zeta**2), rel=1e-3)


def test_damper_dissipation_closes_the_span_energy_balance(runner):
    d = mode_decay(runner("ConductorSpan"), runner("DamperElement"), mode=5, x_d=1.0)
    assert abs(d.balance_error) <= 0.02  # the bar; measured 7e-5
    assert d.damper > 2 * d.self_damping  # near its 10 Hz resonance the damper dominates
    assert d.amplitude_ratio < 0.4  # measured 0.28


def test_a_damper_at_a_node_of_the_mode_does_nothing(runner):
    d = mode_decay(runner("ConductorSpan"), runner("DamperElement"), mode=15, x_d=2.0)  # 2 m = L/15: a node
    assert d.amplitude_ratio == pytest.approx(1.0, abs=0.01)
