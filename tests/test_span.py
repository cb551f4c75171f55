"""Conductor span FMU and the span + damper co-simulation: analytic decay, energy balance, damper at a node."""
import numpy as np

from pyfit.runtime.cosim import cosimulate
from pyfit.design.span import mode_decay

C = np.sqrt(28000.0 / 1.628)  # m/s, wave speed of the default span (T = 28 kN, m_l = 1.628 kg/m)


def test_span_mode_decays_at_its_analytic_frequency_and_damping(runner, measured):
    n, zeta = 5, 0.002
    f = n * C / (2 * 30.0)
    stop = 0.0001 * round(2.0 / 0.0001)
    r = cosimulate({"span": runner("ConductorSpan")}, [], stop, 1e-4, ["span.E", "span.q[5]"],
                   {"span": {"exc_type": 0, "q[5]": 5e-3, "m_c": 0.0}})  # bare span
    t = r.time
    # energy of a viscously damped mode: E0 exp(-2 zeta w t) (to first order in zeta)
    rate = -np.polyfit(t, np.log(r["span.E"]), 1)[0]
    measured("span FMU, bare, mode 5 free decay: energy decay rate vs 2ζω, relative error", abs(rate / (2 * zeta * 2 * np.pi * f) - 1), 0.01)
    crossings = np.nonzero(np.diff(np.sign(r["span.q[5]"])) != 0)[0]
    f_measured = (len(crossings) - 1) / 2 / (t[crossings[-1]] - t[crossings[0]])
    measured("span FMU, bare, mode 5: frequency from zero crossings vs n·c/2L·√(1−ζ²), relative error",
             abs(f_measured / (f * np.sqrt(1 - zeta**2)) - 1), 1e-3)


def test_damper_dissipation_closes_the_span_energy_balance(runner, measured):
    d = mode_decay(runner("ConductorSpan"), runner("DamperElement"), mode=5, x_d=1.0)
    measured("span + damper co-simulation, mode 5 decay: (span energy loss − self-damping − ∫F_clamp·v_clamp dt) / loss",
             abs(d.balance_error), 5e-4)  # the coupling step's error, O(h²)
    assert d.damper > 2 * d.self_damping  # near its 10 Hz resonance the damper dominates
    measured("span + damper, mode 5 (10.9 Hz), damper at 1 m: resonant amplitude ratio with / without", d.amplitude_ratio, 0.4)


def test_a_damper_at_a_node_of_the_mode_does_nothing(runner, measured):
    d = mode_decay(runner("ConductorSpan"), runner("DamperElement"), mode=15, x_d=2.0)  # 2 m = L/15: a node
    measured("span + damper at a node (mode 15, 2 m = L/15): |amplitude ratio − 1|", abs(d.amplitude_ratio - 1), 0.01)
