"""Energy and momentum balances of the TwoDOF system, from the FMU's simulated signals."""
import numpy as np
import pytest
from scipy.integrate import trapezoid

DT = 1e-4
M1, M2, K1, K2, K12, C1, C2, C12 = 0.5, 1.0, 2000.0, 5000.0, 500.0, 5.0, 2.0, 1.0


def _energy(config, r, k_nl):
    y1, y2, v1, v2 = r["y1"], r["y2"], r["v1"], r["v2"]
    d = y2 - y1
    cubic = 0.25 * k_nl * (y2**4 if config == "c" else d**4)
    return 0.5 * M1 * v1**2 + 0.5 * M2 * v2**2 + 0.5 * K1 * y1**2 + 0.5 * K2 * y2**2 + 0.5 * K12 * d**2 + cubic


@pytest.mark.parametrize("config", "cd")
def test_input_work_equals_dissipation_plus_energy_change_without_bouc_wen(runner, config, measured):
    k_nl = 1e6
    params = {"alpha": 0.0, "k_nl": k_nl, "exc_type": 2, "exc_rate": 6.0, "exc_amplitude": 10.0}
    r = runner(f"TwoDOF{config}").simulate(8.0, DT, ["y1", "y2", "v1", "v2", "F"], params, tolerance=1e-11)
    assert r.ok
    work = trapezoid(r["F"] * r["v1"], r.time)
    dissipated = trapezoid(C1 * r["v1"] ** 2 + C2 * r["v2"] ** 2 + C12 * (r["v2"] - r["v1"]) ** 2, r.time)
    e = _energy(config, r, k_nl)
    assert np.max(np.abs(r["y2"])) ** 3 * k_nl > 0.01 * K2 * np.max(np.abs(r["y2"]))  # cubic term matters
    measured(f"TwoDOF{config} without Bouc-Wen, 8 s sweep: |input work − (viscous dissipation + ΔE)| / work",
             abs(work - (dissipated + e[-1] - e[0])) / abs(work), 1e-3)


# sine frequency [Hz] and force amplitude [N] at which the hysteresis loop is clearly open
LOOP_LEVELS = {"a": (11.0, 20.0), "b": (3.0, 40.0), "c": (11.0, 20.0), "d": (3.0, 40.0)}


@pytest.mark.parametrize("config", "abcd")
def test_steady_cycle_input_work_equals_viscous_plus_bouc_wen_loop_area(runner, config, measured):
    f_exc, amplitude = LOOP_LEVELS[config]
    params = {"exc_type": 1, "exc_f_start": f_exc, "exc_amplitude": amplitude}
    outputs = ["y1", "y2", "v1", "v2", "F", "z", "boucWen.v_rel"]
    r = runner(f"TwoDOF{config}").simulate(8.0, DT, outputs, params, tolerance=1e-11)
    assert r.ok
    n = int(round(1 / f_exc / DT))
    sl = slice(len(r.time) - 1 - n, len(r.time))  # the last whole period
    t = r.time[sl]
    work = trapezoid(r["F"][sl] * r["v1"][sl], t)
    viscous = trapezoid(C1 * r["v1"][sl] ** 2 + C2 * r["v2"][sl] ** 2 + C12 * (r["v2"][sl] - r["v1"][sl]) ** 2, t)
    loop_area = trapezoid(r["z"][sl] * r["boucWen.v_rel"][sl], t)  # closed-loop integral of z d(s_rel)
    assert loop_area > 0.02 * work  # hysteresis dissipates a visible share
    measured(f"TwoDOF{config} with Bouc-Wen, steady sine cycle: |input work − (viscous + loop area ∮z·dr)| / work",
             abs(work - (viscous + loop_area)) / abs(work), 5e-3)


@pytest.mark.parametrize("config", "abcd")
def test_total_momentum_balance(runner, config, measured):
    params = {"exc_type": 2, "exc_rate": 6.0}
    outputs = ["mass1.a", "mass2.a", "F", "fixed.flange.f"]
    r = runner(f"TwoDOF{config}").simulate(6.0, 1e-3, outputs, params, tolerance=1e-10)
    assert r.ok
    # sum of m*a = external force + reaction of the ground on the system (= -fixed.flange.f)
    lhs = M1 * r["mass1.a"] + M2 * r["mass2.a"]
    rhs = r["F"] - r["fixed.flange.f"]
    measured(f"TwoDOF{config}: Σm·ÿ vs external force − ground reaction, max|Δ| / max|F|",
             np.max(np.abs(lhs - rhs)) / np.max(np.abs(r["F"])), 1e-9)
