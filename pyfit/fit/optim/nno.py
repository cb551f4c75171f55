"""Neural Network Optimization (thesis chapter 3, theory §4).

(I) true evaluations at init_sim Sobol points; (II) train the MLP surrogate on all (x, residual vector);
(III) minimise the surrogate's sum of squares with a GA (pymoo) warm-started from its previous
population; (IV) evaluate the FMU at the GA optimum; (V-VII) append, retrain, repeat. Stops when the
latest true error < fun_tol, or when the relative change of x < x_tol and of the residual < y_tol
(stall), or after max_sim true evaluations. Returns the best point ever evaluated.

Two options beyond the thesis, both off by default:
- a search transform: the surrogate learns, and the GA and the trust region minimise, sum(g(r)^2) for a
  transform g of the residual vector, while the true errors recorded and the point returned are those of
  sum(r^2). The thesis's relative PSD error r = (P - P_meas)/P_meas spans 1e-3..1e4 across the bounds,
  which 20-60 samples cannot teach an MLP; g(r) = log1p(r) = log(P/P_meas) is smooth in the parameters
  and has the same minimiser where the model fits.
- a trust region: the GA searches a box of half-width `radius` around the best point so far; the radius
  doubles when the true error falls by at least 3/4 of what the surrogate predicted, halves when it falls
  by less than 1/4 (or rises), and stays within [x_tol, 0.5]; the surrogate is trained on the points
  within twice the radius (at least the 2 n + 2 nearest), so it resolves what a global fit smooths over.
"""
from __future__ import annotations

import time
import warnings
from collections.abc import Callable


import numpy as np
from pymoo.algorithms.soo.nonconvex.ga import GA
from pymoo.core.problem import Problem
from pymoo.optimize import minimize
from scipy.stats import qmc

from pyfit.fit.optim.result import OptimResult
from pyfit.io.fit_config import NNOSettings
from pyfit.fit.optim.surrogate import Surrogate


class _SurrogateProblem(Problem):
    def __init__(self, surrogate: Surrogate, lower: np.ndarray, upper: np.ndarray):
        super().__init__(n_var=len(lower), n_obj=1, xl=lower, xu=upper)
        self.surrogate = surrogate

    def _evaluate(self, X, out, *args, **kwargs):
        out["F"] = self.surrogate.predict_error(X)[:, None]  # the whole population in one forward pass


def sobol_points(n: int, d: int, seed: int) -> np.ndarray:
    """n scrambled Sobol points in [0, 1]^d (space-filling initial design)."""
    with warnings.catch_warnings():  # any n is fine for a design; powers of two only balance better
        warnings.simplefilter("ignore", UserWarning)
        return qmc.Sobol(d, scramble=True, seed=seed).random(n)


def _local(X: np.ndarray, G: np.ndarray, centre: np.ndarray, radius: float, n_var: int):
    """The training set of a trust-region step: the points within twice the radius of the centre (max norm),
    and at least the 2 n_var + 2 nearest."""
    dist = np.max(np.abs(X - centre), axis=1)
    keep = dist <= 2 * radius
    if keep.sum() < 2 * n_var + 2:
        keep = np.argsort(dist)[:2 * n_var + 2]
    return X[keep], G[keep]


def _proposal(settings: NNOSettings, X: list, G: list, searched: list, radius: float, population, it: int,
              n_var: int):
    """One NNO step's proposal: the surrogate trained on the points (within the trust region around the best),
    minimised by the GA from the previous population (squeezed into the region). Returns the new point, the
    surrogate, its predicted error there and the GA's last population."""
    best = int(np.argmin(searched))
    Xa, Ga = np.array(X), np.array(G)
    if settings.trust_region:
        lower, upper = np.clip(X[best] - radius, 0, 1), np.clip(X[best] + radius, 0, 1)
        Xa, Ga = _local(Xa, Ga, X[best], radius, n_var)
    else:
        lower, upper = np.zeros(n_var), np.ones(n_var)
    surrogate = Surrogate(settings.hidden_sizes, seed=settings.seed + it, max_epochs=settings.max_epochs,
                          patience=settings.patience).fit(Xa, Ga)
    sampling = population
    if settings.trust_region:  # warm start: the previous population, squeezed into the new box
        sampling = np.clip(population, lower, upper)
        sampling[0] = X[best]
    algorithm = GA(pop_size=settings.p_size, sampling=sampling, eliminate_duplicates=True)
    res = minimize(_SurrogateProblem(surrogate, lower, upper), algorithm, ("n_gen", settings.ga_generations),
                   seed=settings.seed + it, verbose=False)
    x_new = np.clip(np.atleast_1d(res.X).astype(float), 0.0, 1.0)
    return x_new, surrogate, float(surrogate.predict_error(x_new[None])[0]), res.pop.get("X")


def _radius(radius: float, ratio: float, x_tol: float) -> float:
    """The trust region's next radius from the ratio of the actual to the predicted decrease."""
    return min(2 * radius, 0.5) if ratio > 0.75 else max(radius / 2, x_tol) if ratio < 0.25 else radius


def _stalled(x_new, r_new, last_x, last_r, settings: NNOSettings) -> bool:
    """Whether the point and its residual moved less than x_tol and y_tol (relative) since the last step."""
    if last_x is None:
        return False
    dx = np.linalg.norm(x_new - last_x) / max(np.linalg.norm(last_x), 1e-12)
    dr = np.linalg.norm(r_new - last_r) / max(np.linalg.norm(last_r), 1e-12)
    return dx < settings.x_tol and dr < settings.y_tol


def nno(residuals, n_var: int, settings: NNOSettings, x0: np.ndarray | None = None, callback=None,
        transform: Callable | None = None) -> OptimResult:
    """Minimise sum(residuals(x)^2) over x in [0, 1]^n_var with NNO; residuals returns a finite vector.
    transform: the surrogate learns transform(r) and the search minimises its sum of squares (see above)."""
    t_start = time.perf_counter()
    g = transform or (lambda r: r)
    rng = np.random.default_rng(settings.seed)
    X = sobol_points(settings.init_sim, n_var, settings.seed)
    if x0 is not None:
        X[0] = x0
    R = [residuals(x) for x in X]
    errors = [float(np.sum(r**2)) for r in R]
    G = [g(r) for r in R]
    searched = [float(np.sum(v**2)) for v in G]  # the errors the surrogate and the trust region work on
    history = [{"iteration": 0, "evaluations": i + 1, "x": X[i].tolist(), "true_error": errors[i],
                "ann_error": None, "wall_s": time.perf_counter() - t_start} for i in range(len(X))]
    X, population, last_x, last_r, radius, stop, it = list(X), None, None, None, 0.5, "max_sim", 0
    while len(X) < settings.max_sim:
        it += 1
        best = int(np.argmin(searched))
        population = rng.random((settings.p_size, n_var)) if population is None else population
        x_new, surrogate, ann_error, population = _proposal(settings, X, G, searched, radius, population, it, n_var)
        r_new = residuals(x_new)
        err, g_new = float(np.sum(r_new**2)), g(r_new)
        searched_new = float(np.sum(g_new**2))
        if settings.trust_region:
            predicted = float(surrogate.predict_error(X[best][None])[0]) - ann_error
            radius = _radius(radius, (searched[best] - searched_new) / predicted if predicted > 0 else -1.0,
                             settings.x_tol)
        X.append(x_new)
        G.append(g_new)
        errors.append(err)
        searched.append(searched_new)
        history.append({"iteration": it, "evaluations": len(X), "x": x_new.tolist(), "true_error": err,
                        "ann_error": ann_error, "ann_validation_loss": surrogate.validation_loss,
                        "radius": radius if settings.trust_region else None,
                        "searched_error": searched_new if transform else None,
                        "wall_s": time.perf_counter() - t_start})
        if callback:
            callback(history[-1])
        if err < settings.fun_tol:
            stop = "fun_tol"
            break
        if _stalled(x_new, r_new, last_x, last_r, settings):
            stop = "stall"
            break
        last_x, last_r = x_new, r_new
    best = int(np.argmin(errors))
    return OptimResult(np.array(X[best]), errors[best], len(X), stop, history, time.perf_counter() - t_start)
