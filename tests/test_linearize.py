"""Modes of an FMU linearised at rest against analytic and independently assembled values."""
import numpy as np

from damper_matrices import clamped_matrices
from pyfit.analysis.modal import state_space_modes
from pyfit.runtime.linearize import linear_modes


def test_sdof_mode_is_the_analytic_one(fmu_dir, measured):
    (mode,) = linear_modes(fmu_dir / "SDOFBoucWen.fmu", {"alpha": 0.0, "k": 1e5, "exc_type": 0})
    f_n = np.sqrt(1e5 / 2.0) / (2 * np.pi)
    zeta = 10.0 / (2 * np.sqrt(1e5 * 2.0))
    measured("SDOF FMU linearised at rest (A by central differences of fmi2GetDerivatives): |f_n / √(k/m)/2π − 1|",
             abs(mode.f_n / f_n - 1), 1e-8)
    measured("the same: |ζ / (c / 2√(km)) − 1|", abs(mode.zeta / zeta - 1), 1e-6)


def test_damper_modes_match_independently_assembled_matrices(fmu_dir, measured):
    linear = {"exc_type": 0, "k_bw1": 0.0, "k_bw2": 0.0, "k_cs1": 0.0, "k_cs2": 0.0}
    got = linear_modes(fmu_dir / "StockbridgeDamper.fmu", linear)
    ref = state_space_modes(*clamped_matrices())
    assert len(got) == 4
    worst = max(abs(g.f_n / r.f_n - 1) for g, r in zip(got, ref))
    measured("damper FMU linearised at rest: natural frequencies vs eigenvalues of independently assembled "
             "M, C, K, max relative error", worst, 1e-6)
    measured("the same: damping ratios, max relative error", max(abs(g.zeta / r.zeta - 1) for g, r in zip(got, ref)),
             1e-5)


def test_reference_damper_modes_match_the_fmu_for_a_drawn_geometry(fmu_dir, measured):
    """The campaign's damper geometry (pyfit.gap.campaign.damper_geometry) sets its test band from the CasADi
    reference's modes (pyfit.reference.models.damper_modes_hz): they must be the FMU's, within the damping's
    shift of an undamped frequency (ζ ≤ 5 %: f_n as |λ| is the undamped one exactly for proportional damping)."""
    from pyfit.gap.campaign import damper_geometry
    from pyfit.reference.models import damper_modes_hz

    geometry, band = damper_geometry(np.random.default_rng(11))
    linear = {"exc_type": 0, "k_bw1": 0.0, "k_bw2": 0.0, "k_cs1": 0.0, "k_cs2": 0.0, **geometry}
    got = [m.f_n for m in linear_modes(fmu_dir / "StockbridgeDamper.fmu", linear)]
    ref = damper_modes_hz(geometry)
    measured("campaign damper (random geometry): reference undamped frequencies vs the FMU linearised at rest, "
             "max relative error", max(abs(g / r - 1) for g, r in zip(got, ref)), 1e-6)
    assert band[0] < got[0] < got[1] < band[1]
