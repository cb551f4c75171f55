"""Linear limits: modal parameters ESTIMATED from simulated free decays (ERA) against independent
computations (analytic formulas, numpy eigenvalues of independently assembled matrices)."""
import numpy as np
import pytest

from damper_matrices import clamped_matrices
from pyfit.analysis.modal import free_decay_modes, state_space_modes
from pyfit.gap.effects import candidates

DT = 5e-4
# ERA on a noise-free decay integrated at rtol 1e-11 is exact up to the integrator's error (about 1e-10 of
# the frequencies and damping ratios measured); 1e-8 leaves two decades for other machines' rounding, and a
# wrong matrix entry, sign or unit moves a mode by far more.
ERA_TOL = 1e-8


def test_sdof_linear_limit_natural_frequency_and_damping(runner, measured):
    # beta = 0: z = alpha*y exactly when the decay starts from y = 0 with an initial velocity
    res = runner("SDOFBoucWen").simulate(1.0, DT, ["y"], {"beta": 0.0, "exc_type": 0, "mass.v": 0.1},
                                         tolerance=1e-11)
    assert res.ok
    (mode,) = free_decay_modes(res["y"], DT, 1)
    m, c, k, alpha = 2.0, 10.0, 5e4, 5e4
    f0 = np.sqrt((k + alpha) / m) / (2 * np.pi)  # 35.59 Hz, thesis Table 4.2
    zeta = c / (2 * np.sqrt((k + alpha) * m))  # 1.12 %
    measured("SDOF β = 0: natural frequency estimated by ERA from a free decay vs √((k+α)/m)/2π, relative error",
             abs(mode.f_n / f0 - 1), ERA_TOL)
    measured("the same decay: damping ratio by ERA vs c/(2√((k+α)m)), relative error", abs(mode.zeta / zeta - 1),
             ERA_TOL)


def _two_dof_matrices(config, alpha):
    m1, m2, k1, k2, k12, c1, c2, c12 = 0.5, 1.0, 2000.0, 5000.0, 500.0, 5.0, 2.0, 1.0
    M = np.diag([m1, m2])
    K = np.array([[k1 + k12, -k12], [-k12, k2 + k12]])
    C = np.array([[c1 + c12, -c12], [-c12, c2 + c12]])
    if config in "ac":  # linearised Bouc-Wen (stiffness alpha) between mass 2 and ground
        K = K + np.array([[0, 0], [0, alpha]])
    else:  # between the masses
        K = K + alpha * np.array([[1, -1], [-1, 1]])
    return M, C, K


@pytest.mark.parametrize("config", "abcd")
def test_two_dof_linear_modes_match_numpy_eigenvalues(runner, config, measured):
    params = {"beta": 0.0, "exc_type": 0, "mass1.v": 0.05}
    if config in "cd":
        params["k_nl"] = 0.0
    res = runner(f"TwoDOF{config}").simulate(2.0, DT, ["y1", "y2"], params, tolerance=1e-11)
    assert res.ok
    est = free_decay_modes(np.column_stack([res["y1"], res["y2"]]), DT, 2)
    ref = state_space_modes(*_two_dof_matrices(config, alpha=500.0))
    measured(f"TwoDOF{config}, linearised: damped frequencies by ERA vs numpy eigenvalues of hand-assembled M, C, K, "
             "max relative error", max(abs(e.f_d / r.f_d - 1) for e, r in zip(est, ref)), ERA_TOL)
    measured(f"TwoDOF{config}: damping ratios by ERA vs the eigenvalues, max relative error",
             max(abs(e.zeta / r.zeta - 1) for e, r in zip(est, ref)), ERA_TOL)


def test_damper_reference_matrices_have_the_design_frequencies():
    M, _, K = clamped_matrices()
    undamped = np.sqrt(np.sort(np.linalg.eigvals(np.linalg.solve(M, K)).real)) / (2 * np.pi)
    np.testing.assert_allclose(undamped, [10.1, 17.3, 79.0, 125.0], rtol=0.01)


def _damper_pulse_modes(runner, params):
    """ERA modes of the damper FMU (`params` over its defaults) ringing down after a smooth 10 ms clamp pulse
    (exact x, v, a), the clamp then at rest."""
    T = 0.01
    t = np.arange(0, 1.0 + DT / 2, DT / 4)
    s = np.clip(t / T, 0, 1)
    x = 1e-3 * np.sin(np.pi * s) ** 4
    v = np.gradient(x, t)
    a = np.gradient(v, t)
    res = runner("StockbridgeDamper").simulate(1.0, DT, ["x1", "x2", "phi1", "phi2"],
                                               {"k_cs1": 0.0, "k_cs2": 0.0, "exc_type": 0, **params},
                                               inputs={"x_base": x, "v_base": v, "a_base": a}, input_time=t,
                                               tolerance=1e-11)
    assert res.ok
    keep = res.time > 2 * T
    return free_decay_modes(np.column_stack([res[o][keep] for o in ("x1", "x2", "phi1", "phi2")]), DT, 4)


def test_damper_linear_modes_match_independent_matrices(runner, measured):
    est = _damper_pulse_modes(runner, {"k_bw1": 0.0, "k_bw2": 0.0})
    ref = state_space_modes(*clamped_matrices())
    assert len(est) == 4
    measured("damper, nonlinear elements off: damped frequencies by ERA from a clamp-pulse decay vs eigenvalues of "
             "independently assembled matrices, max relative error", max(abs(e.f_d / r.f_d - 1) for e, r in zip(est, ref)),
             ERA_TOL)


def test_the_damper_loop_reduced_to_its_linear_part_is_a_spring_on_each_arm(runner, measured):
    """The diagnosis's linear comparator of a loop (Effect.linear_parts): the loop closed, before and after yield,
    is a spring of k_bw, or a_bw k_bw, between each mass and the clamp: the independent matrices with it added to
    the masses' translations (the beam's Rayleigh damping unchanged). A loop drawn at random."""
    rng = np.random.default_rng(20261202)
    loop = {"k_bw1": rng.uniform(200, 2000), "k_bw2": rng.uniform(200, 2000), "a_bw": rng.uniform(0.1, 0.9),
            "beta": rng.uniform(0.5, 3), "gamma": rng.uniform(-1, 1), "nu": rng.uniform(1, 3)}
    M, C, K = clamped_matrices()
    worst = 0.0
    for part in candidates("damper")["hysteresis"].linear_parts(loop):
        closed = {**loop, **part}
        springs = np.zeros_like(K)
        springs[0, 0], springs[2, 2] = closed["k_bw1"], closed["k_bw2"]  # x1, x2 among the free DOFs
        est, ref = _damper_pulse_modes(runner, closed), state_space_modes(M, C, K + springs)
        assert len(est) == 4
        worst = max(worst, *(abs(e.f_d / r.f_d - 1) for e, r in zip(est, ref)))
    measured("damper loop reduced to its linear part (before and after yield, a random loop): damped frequencies "
             "by ERA vs independent matrices with a spring per arm, max relative error", worst, ERA_TOL)
