"""Baselines at equal true-evaluation budgets, the local polish, and identifiability at the optimum.

All work on unit-scaled parameters x in [0, 1]^n and a residual function r(x) (error = sum r^2).
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import scipy.optimize

from pyfit.fit.optim.result import OptimResult


class _Budget(Exception):
    pass


class CountingResiduals:
    """Wraps r(x): counts true evaluations, keeps the history and the best point, enforces a budget."""

    def __init__(self, residuals, budget: int, target: float | None = None):
        self.residuals = residuals
        self.budget = budget
        self.target = target
        self.history: list[dict] = []
        self.best_x, self.best_error = None, np.inf
        self.reached_at: int | None = None
        self.t0 = time.perf_counter()

    def __call__(self, x):
        if len(self.history) >= self.budget:
            raise _Budget
        x = np.clip(np.asarray(x, float), 0.0, 1.0)
        r = self.residuals(x)
        err = float(np.sum(r**2))
        self.history.append({"evaluations": len(self.history) + 1, "x": x.tolist(), "true_error": err,
                             "wall_s": time.perf_counter() - self.t0})
        if err < self.best_error:
            self.best_x, self.best_error = x, err
        if self.target is not None and self.reached_at is None and err <= self.target:
            self.reached_at = len(self.history)
        return r

    def result(self, reason: str) -> OptimResult:
        return OptimResult(np.array(self.best_x), self.best_error, len(self.history), reason, self.history,
                           time.perf_counter() - self.t0)


def ga_direct(residuals, n_var: int, budget: int, pop_size: int = 20, seed: int = 0,
              target: float | None = None) -> tuple[OptimResult, int | None]:
    """The GA applied directly to the FMU objective (the thesis's comparison). Returns the result and the
    number of evaluations at which the error first reached `target` (None if never)."""
    from pymoo.algorithms.soo.nonconvex.ga import GA
    from pymoo.core.problem import ElementwiseProblem
    from pymoo.optimize import minimize

    counter = CountingResiduals(residuals, budget, target)

    class P(ElementwiseProblem):
        def __init__(self):
            super().__init__(n_var=n_var, n_obj=1, xl=np.zeros(n_var), xu=np.ones(n_var))

        def _evaluate(self, x, out, *args, **kwargs):
            out["F"] = float(np.sum(counter(x) ** 2))
            if target is not None and counter.reached_at is not None:
                raise _Budget

    reason = "budget"
    try:
        minimize(P(), GA(pop_size=pop_size, eliminate_duplicates=True), ("n_evals", budget + pop_size), seed=seed,
                 verbose=False)
    except _Budget:
        reason = "target" if counter.reached_at is not None else "budget"
    return counter.result(reason), counter.reached_at


def differential_evolution(residuals, n_var: int, budget: int, seed: int = 0, popsize: int = 10) -> OptimResult:
    """scipy's differential evolution on the FMU objective, stopped at `budget` true evaluations."""
    counter = CountingResiduals(residuals, budget)
    reason = "converged"
    try:
        scipy.optimize.differential_evolution(lambda x: float(np.sum(counter(x) ** 2)), [(0.0, 1.0)] * n_var,
                                              seed=seed, popsize=popsize, polish=False, tol=0, maxiter=10**6)
    except _Budget:
        reason = "budget"
    return counter.result(reason)


def polish(residuals, x0: np.ndarray, budget: int = 200, diff_step: float = 1e-4, margin: float = 0.01
           ) -> OptimResult:
    """Local least squares (scipy least_squares, trust-region reflective) on the residual vector.

    The start is moved at least `margin` (a share of the range) off the bounds: the trust-region-reflective
    scaling (Coleman-Li) gives a variable sitting on its bound a zero step, and it then creeps off it by
    doubling steps from ~1e-7, which can use the whole budget (seen with an effect started at zero)."""
    counter = CountingResiduals(residuals, budget)
    reason = "converged"
    try:
        scipy.optimize.least_squares(counter, np.clip(x0, margin, 1.0 - margin), bounds=(0.0, 1.0),
                                     diff_step=diff_step, x_scale="jac", max_nfev=budget)
    except _Budget:
        reason = "budget"
    return counter.result(reason)


@dataclass
class Identifiability:
    """Gauss-Newton uncertainty at the optimum, in the parameters' SI units."""

    names: list[str]
    values: list[float]
    std: list[float]
    correlation: list[list[float]]
    singular_values: list[float]
    correlated_pairs: list[tuple[str, str, float]]


def identifiability(residuals, x: np.ndarray, variables, step: float = 1e-4, noise_var: float | None = None
                    ) -> Identifiability:
    """Covariance sigma^2 (J^T J)^-1 from a central-difference Jacobian of the residual vector at x.

    sigma^2 defaults to the residual variance sum(r^2)/(m - n). Reports standard deviations, the
    correlation matrix, the singular values of the Jacobian scaled to the bounds, and |rho| > 0.95 pairs.
    """
    x = np.asarray(x, float)
    r0 = residuals(x)
    m, n = len(r0), len(x)
    J = np.empty((m, n))
    for j in range(n):
        h = step if x[j] + step <= 1 else -step
        lo = max(0.0, x[j] - abs(h)) if 0 < x[j] - abs(h) else x[j]
        hi = min(1.0, x[j] + abs(h))
        xp, xm = x.copy(), x.copy()
        xp[j], xm[j] = hi, lo
        J[:, j] = (residuals(xp) - residuals(xm)) / (hi - lo)
    s2 = noise_var if noise_var is not None else float(np.sum(r0**2)) / max(m - n, 1)
    sv = np.linalg.svd(J, compute_uv=False)
    cov_u = s2 * np.linalg.pinv(J.T @ J)
    span = np.array([v.upper - v.lower for v in variables])
    cov = cov_u * np.outer(span, span)
    std = np.sqrt(np.clip(np.diag(cov), 0, None))
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(std, std)
    names = [v.name for v in variables]
    pairs = [(names[i], names[j], float(corr[i, j])) for i in range(n) for j in range(i + 1, n)
             if np.isfinite(corr[i, j]) and abs(corr[i, j]) > 0.95]
    return Identifiability(names, [v.value(u) for v, u in zip(variables, x)], std.tolist(),
                           np.nan_to_num(corr).tolist(), sv.tolist(), pairs)
