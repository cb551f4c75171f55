"""The fitting objective of a damper characteristic test (IEC 61897 / IEEE 664): the damper FMU's clamp
impedance against a measured one at every test frequency and level.

Residuals: (Z_sim − Z_meas) / |Z_meas| as real and imaginary parts, so that every test point weighs the
same whatever its magnitude (a relative error ε in |Z|, or ε rad in phase, gives a residual of size ε). The
simulations are the damper table runs of the energy balance (a clamp sine, settled, first harmonics over
whole periods). A failed run gives the penalty on its residuals; nothing non-finite leaves this module.
"""
from __future__ import annotations

import numpy as np

from pyfit.runtime.damper_power import damper_power_table
from pyfit.io.fit_config import FreeParameter
from pyfit.io.impedance import ImpedanceTest


def model_impedance(fmu, test: ImpedanceTest, params: dict, workers: int | None = 1) -> np.ndarray:
    """The FMU's clamp impedance [N·s/m] at the test's frequencies and amplitudes (NaN where a run failed)."""
    return damper_power_table(fmu, test.frequencies, test.amplitudes, params, workers=workers,
                              progress=False).impedance


def relative_residuals(z: np.ndarray, test: ImpedanceTest, penalty: float = 10.0) -> np.ndarray:
    """(z − Z_meas) / |Z_meas| as real and imaginary parts, the penalty where z is not finite."""
    rel = (z - test.impedance) / np.abs(test.impedance)
    r = np.concatenate([rel.real.ravel(), rel.imag.ravel()])
    return np.where(np.isfinite(r), r, penalty)


class ImpedanceObjective:
    """Residual vector r(x) of unit-scaled parameters x; error = sum(r^2)."""

    def __init__(self, fmu: str, test: ImpedanceTest, variables: list[FreeParameter], fixed: dict | None = None,
                 penalty: float = 10.0, workers: int | None = 1):
        self.fmu = str(fmu)
        self.test = test
        self.variables = variables
        self.fixed = dict(fixed or {})
        self.penalty = penalty
        self.workers = workers
        self.size = 2 * test.impedance.size

    def params(self, x) -> dict:
        """FMU parameters (SI) for unit-scaled x."""
        p = dict(self.fixed)
        p.update({v.name: v.value(u) for v, u in zip(self.variables, np.clip(x, 0.0, 1.0))})
        return p

    def impedance(self, x) -> np.ndarray:
        """The FMU's clamp impedance [N·s/m] at the test's frequencies and amplitudes (NaN where a run failed)."""
        return model_impedance(self.fmu, self.test, self.params(x), self.workers)

    def residuals(self, x) -> np.ndarray:
        """Residual vector (finite; the penalty where a simulation failed)."""
        return relative_residuals(self.impedance(x), self.test, self.penalty)

    def __call__(self, x) -> float:
        return float(np.sum(self.residuals(x) ** 2))

    def errors(self, x) -> dict[str, float]:
        """Largest |Z| error [%] and phase error [deg] over the test points."""
        z = self.impedance(x)
        meas = self.test.impedance
        return {"magnitude_percent_max": float(100 * np.nanmax(np.abs(np.abs(z) / np.abs(meas) - 1))),
                "phase_deg_max": float(np.degrees(np.nanmax(np.abs(np.angle(z / meas)))))}

    def close(self):
        """Nothing to release (the runs are made per evaluation)."""
