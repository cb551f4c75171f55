"""Neural Network Optimization (seed chapter 3, design section 4).

(I) true evaluations at init_sim Sobol points; (II) train the MLP surrogate on all (x, residual vector);
(III) minimise the surrogate's sum of squares with a GA (pymoo) warm-started from its previous
population; (IV) evaluate the FMU at the GA optimum; (V-VII) append, retrain, repeat. Stops when the
latest true error < fun_tol, or when the relative change of x < x_tol and of the residual < y_tol
(stall), or after max_sim true evaluations. Returns the best point ever evaluated.
"""
from __future__ import annotations

import time
import warnings
from dataclasses import dataclass, field

import numpy as np
from pymoo.algorithms.soo.nonconvex.ga import GA
from pymoo.core.problem import Problem
from pymoo.optimize import minimize
from scipy.stats import qmc

from .surrogate import Surrogate


@dataclass
class NNOSettings:
    """The seed's NNO settings (Tables 4.5, 5.2, 5.7)."""

    init_sim: int = 20
    hidden_sizes: list[int] = field(default_factory=lambda: [15])
    p_size: int = 10
    fun_tol: float = 5e-4
    max_sim: int = 60
    x_tol: float = 1e-3
    y_tol: float = 1e-3
    ga_generations: int = 60
    seed: int = 0


@dataclass
class OptimResult:
    """Best point ever evaluated (unit-scaled), its error, the number of true evaluations and the history."""

    x: np.ndarray
    error: float
    n_evaluations: int
    stop_reason: str
    history: list[dict]
    wall_s: float


class _SurrogateProblem(Problem):
    def __init__(self, surrogate: Surrogate, n_var: int):
        super().__init__(n_var=n_var, n_obj=1, xl=np.zeros(n_var), xu=np.ones(n_var))
        self.surrogate = surrogate

    def _evaluate(self, X, out, *args, **kwargs):
        out["F"] = self.surrogate.predict_error(X)[:, None]  # the whole population in one forward pass


def sobol_points(n: int, d: int, seed: int) -> np.ndarray:
    """n scrambled Sobol points in [0, 1]^d (space-filling initial design)."""
    with warnings.catch_warnings():  # any n is fine for a design; powers of two only balance better
        warnings.simplefilter("ignore", UserWarning)
        return qmc.Sobol(d, scramble=True, seed=seed).random(n)


def nno(residuals, n_var: int, settings: NNOSettings, x0: np.ndarray | None = None, callback=None) -> OptimResult:
    """Minimise sum(residuals(x)^2) over x in [0, 1]^n_var with NNO; residuals returns a finite vector."""
    t_start = time.perf_counter()
    rng = np.random.default_rng(settings.seed)
    X = sobol_points(settings.init_sim, n_var, settings.seed)
    if x0 is not None:
        X[0] = x0
    R = [residuals(x) for x in X]
    history = [{"iteration": 0, "evaluations": i + 1, "x": X[i].tolist(), "true_error": float(np.sum(r**2)),
                "ann_error": None, "wall_s": time.perf_counter() - t_start} for i, r in enumerate(R)]
    X = list(X)
    population = None
    last_x, last_r = None, None
    stop = "max_sim"
    it = 0
    while len(X) < settings.max_sim:
        it += 1
        surrogate = Surrogate(settings.hidden_sizes, seed=settings.seed + it).fit(np.array(X), np.array(R))
        problem = _SurrogateProblem(surrogate, n_var)
        sampling = population if population is not None else rng.random((settings.p_size, n_var))
        algorithm = GA(pop_size=settings.p_size, sampling=sampling, eliminate_duplicates=True)
        res = minimize(problem, algorithm, ("n_gen", settings.ga_generations), seed=settings.seed + it,
                       verbose=False)
        population = res.pop.get("X")
        x_new = np.clip(np.atleast_1d(res.X).astype(float), 0.0, 1.0)
        ann_error = float(surrogate.predict_error(x_new[None])[0])
        r_new = residuals(x_new)
        err = float(np.sum(r_new**2))
        X.append(x_new)
        R.append(r_new)
        history.append({"iteration": it, "evaluations": len(X), "x": x_new.tolist(), "true_error": err,
                        "ann_error": ann_error, "ann_validation_loss": surrogate.validation_loss,
                        "wall_s": time.perf_counter() - t_start})
        if callback:
            callback(history[-1])
        if err < settings.fun_tol:
            stop = "fun_tol"
            break
        if last_x is not None:
            dx = np.linalg.norm(x_new - last_x) / max(np.linalg.norm(last_x), 1e-12)
            dr = np.linalg.norm(r_new - last_r) / max(np.linalg.norm(last_r), 1e-12)
            if dx < settings.x_tol and dr < settings.y_tol:
                stop = "stall"
                break
        last_x, last_r = x_new, r_new
    errors = [float(np.sum(r**2)) for r in R]
    best = int(np.argmin(errors))
    return OptimResult(np.array(X[best]), errors[best], len(X), stop, history, time.perf_counter() - t_start)
