"""Natural frequencies and damping ratios of any FMU at rest: the state matrix A = ∂ẋ/∂x by central
differences of fmi2GetDerivatives (Model Exchange) around the initial state, inputs at zero, and its
eigenvalues. Used to check that a test's excited band covers the model's resonances."""
from __future__ import annotations

import ctypes
from dataclasses import dataclass

import numpy as np

from pyfit.runtime.fmu import FmuRunner


@dataclass(frozen=True)
class Mode:
    """One oscillatory mode: damped natural frequency f_n [Hz] (undamped: |λ|/2π) and damping ratio [-]."""

    f_n: float
    zeta: float


def state_matrix(fmu_path: str, params: dict, step: float = 1e-7) -> np.ndarray:
    """A = ∂ẋ/∂x at the initial state (central differences, step relative to max(|x_j|, 1e-3))."""
    runner = FmuRunner(str(fmu_path), "ModelExchange")
    try:
        fmu = runner.instance()
        fmu.reset()
        fmu.setupExperiment(startTime=0.0)
        runner.set_parameters(fmu, params)
        fmu.enterInitializationMode()
        fmu.exitInitializationMode()
        fmu.enterContinuousTimeMode()
        n = runner.model_description.numberOfContinuousStates
        buf, der = (ctypes.c_double * n)(), (ctypes.c_double * n)()
        fmu.getContinuousStates(buf, n)
        x0 = np.array(buf[:])
        A = np.empty((n, n))
        for j in range(n):
            h = step * max(abs(x0[j]), 1e-3)
            cols = []
            for sign in (1.0, -1.0):
                buf[:] = x0
                buf[j] = x0[j] + sign * h
                fmu.setContinuousStates(buf, n)
                fmu.getDerivatives(der, n)
                cols.append(np.array(der[:]))
            A[:, j] = (cols[0] - cols[1]) / (2 * h)
        fmu.terminate()
        return A
    finally:
        runner.close()


def linear_modes(fmu_path: str, params: dict) -> list[Mode]:
    """The oscillatory modes of the FMU linearised at rest, lowest first (real eigenvalues left out)."""
    lam = np.linalg.eigvals(state_matrix(fmu_path, params))
    osc = lam[lam.imag > 1e-9 * np.max(np.abs(lam))]
    modes = [Mode(float(abs(v) / (2 * np.pi)), float(-v.real / abs(v))) for v in osc]
    return sorted(modes, key=lambda m: m.f_n)
