"""The textbook alternatives to the gap diagnosis, equation-error methods, run on the same SDOF measurement
files: the restoring-force surface (Masri-Caughey, here as direct parameter estimation: the force balance
regressed on the motion and a library of terms), sparse regression of the dynamics over the same library
(SINDy, pysindy) and NARMAX term selection by the error-reduction ratio (FROLS, sysidentpy).

The shared library of candidate terms and the effects they stand for (`LIBRARY`): y³ (cubic stiffness),
tanh(v/v_s) (Coulomb friction, v_s = 1 % of the velocity RMS), v·|v| (quadratic damping). None of them holds a
hysteretic state (a Bouc-Wen force has memory: no function of the present y and v is one), so these methods
cannot name hysteresis; a sensor delay is not a term of any of them either. A polynomial NARX model (sysidentpy's
Polynomial basis) has the cubic terms only. Each method names the effects of the terms it chooses: a first one
that removes at least SIGNIFICANT of the linear model's residual, a second one that removes NEXT_SIGNIFICANT of
what the first leaves (at most MAX_TERMS: a pair, as the diagnosis can name).

`on_campaign` runs them on every case of a validation campaign (pyfit.gap.campaign), beside the verdict the
diagnosis gave there.

Units: force u [N], displacement y [m], velocity v [m/s], acceleration a [m/s²]; fs [Hz].
"""
from __future__ import annotations

import json
import pathlib
import time
from dataclasses import dataclass

import numpy as np

from pyfit.analysis import kinematics
from pyfit.gap import simulate as sim
from pyfit.gap.effects import peer_terms
from pyfit.io.data import measurement_files, read_measurement

LIBRARY = peer_terms("sdof")  # term -> the effect it stands for (each declared in pyfit.gap.effects)
SIGNIFICANT = 0.01  # a first term is named when it removes at least this share of the linear model's residual
# ... and a second one when it removes this share of what the first leaves: there the sensor noise and the errors
# of the motion derived from the recorded one are most of what is left, and of a single effect's residual the best
# other term removes about 1 % (tests/test_peers.py: a friction oscillator's v|v| term), of a pair's the second
# member tens of per cent
NEXT_SIGNIFICANT = 0.1
MAX_TERMS = 2  # terms named at most (the diagnosis names at most a pair)


@dataclass
class Motion:
    """Force and complete motion of one file (SI), the derived ones band-limited (read_motions)."""

    u: np.ndarray
    y: np.ndarray
    v: np.ndarray
    a: np.ndarray
    fs: float


@dataclass
class Named:
    """One method's verdict on one dataset: the effect named (None: no significant nonlinearity; two effects
    as 'a+b', sorted), each library term's share (what it removes of what the model before it leaves: _stepwise),
    and the wall time."""

    method: str
    effect: str | None
    shares: dict
    wall_s: float
    note: str = ""


def read_motions(folder: pathlib.Path) -> list[Motion]:
    """Every measurement file of an SDOF dataset folder as force and motion (displacement y or acceleration a
    recorded; the rest derived, pyfit.analysis.kinematics)."""
    out = []
    for csv in measurement_files(folder):
        rec = sim.record_of(read_measurement(csv))
        u = rec.inputs["u"][rec.first:]
        recorded = {k: rec.outputs[name] for k, name in (("x", "y"), ("a", "a")) if name in rec.outputs}
        if not recorded:
            raise ValueError(f"{csv}: the equation-error methods need y or a recorded; found "
                             f"{', '.join(rec.outputs)}")
        # the derived signals pass from a third of the excited band's lower edge to three times its top (the third
        # harmonic an odd nonlinearity makes; kinematics.convert), as the diagnosis's own derived signals do
        full = kinematics.complete(recorded, rec.fs, kinematics.excited_band(u, rec.fs), periodic=rec.periodic)
        out.append(Motion(u, full["x"], full["v"], full["a"], rec.fs))
    return out


def _terms(m: Motion, v_s: float) -> dict[str, np.ndarray]:
    return {"y^3": m.y ** 3, "tanh(v/v_s)": np.tanh(m.v / v_s), "v|v|": m.v * np.abs(m.v)}


def _velocity_scale(motions: list[Motion]) -> float:
    return 0.01 * float(np.sqrt(np.mean(np.concatenate([m.v for m in motions]) ** 2)))


def naming_rule() -> str:
    """The rule by which a method names terms, in words (the bench reports state it)."""
    return (f"a method names a first term that removes at least {100 * SIGNIFICANT:g} % of the linear model's "
            f"residual and a second one that removes {100 * NEXT_SIGNIFICANT:g} % of what the first leaves "
            f"(forward selection)")


def _verdict(method: str, shares: dict, chosen: list[str], t0: float, note: str = "") -> Named:
    """The effects of the `chosen` terms ('a+b', sorted; None when none) with every term's share."""
    return Named(method, "+".join(sorted(LIBRARY[n] for n in chosen)) or None, shares, time.perf_counter() - t0, note)


def _unexplained(A: np.ndarray, b: np.ndarray) -> float:
    scale = np.sqrt(np.mean(A ** 2, axis=0))
    coef = np.linalg.lstsq(A / scale, b, rcond=None)[0]
    return float(np.sum((b - (A / scale) @ coef) ** 2))


def _stepwise(terms: list[str], unexplained) -> tuple[dict[str, float], list[str]]:
    """Forward selection of `terms`, `unexplained(chosen)` being the residual sum of squares of the model with the
    terms `chosen` (a list; [] the linear model): each step adds the term that removes most of what the model so
    far leaves, while that is at least SIGNIFICANT of it (NEXT_SIGNIFICANT after the first), up to MAX_TERMS.
    Each term's share: what it removes of what the model before it leaves (a chosen term: at the step it was
    added; the others: at the last step); and the terms chosen, in order."""
    left = unexplained([])
    shares, chosen = {}, []
    while len(chosen) < min(MAX_TERMS, len(terms)):
        after = {n: unexplained(chosen + [n]) for n in terms if n not in chosen}
        shares.update({n: 1.0 - r / left for n, r in after.items()})
        best = min(after, key=after.get)
        if shares[best] < (NEXT_SIGNIFICANT if chosen else SIGNIFICANT):
            break
        chosen.append(best)
        left = after[best]
    return shares, chosen


def restoring_force(motions: list[Motion]) -> Named:
    """The force balance u = m a + c v + k y + Σ θ_j φ_j(y, v) by least squares over every file, the library
    terms chosen by forward selection (_stepwise: stepwise regression, each model fitted anew)."""
    t0 = time.perf_counter()
    v_s = _velocity_scale(motions)
    b = np.concatenate([m.u for m in motions])
    linear = [np.concatenate([getattr(m, k) for m in motions]) for k in ("a", "v", "y")]
    terms = {name: np.concatenate([_terms(m, v_s)[name] for m in motions]) for name in LIBRARY}
    shares, chosen = _stepwise(list(terms), lambda names: _unexplained(
        np.column_stack([*linear, *(terms[n] for n in names)]), b))
    return _verdict("restoring-force surface", shares, chosen, t0)


def sindy(motions: list[Motion], threshold: float = 0.05) -> Named:
    """pysindy: ẋ = Θ(x, u) ξ for x = (y, v) with the library (y, v, u and the candidate terms), sequentially
    thresholded least squares on normalised columns, the measured/derived v and a as ẋ; the candidate terms it
    keeps in the v equation are then ordered and tested by forward selection on that equation (_stepwise), each
    model refitted by least squares: more lenient than SINDy's own coefficients, which on a null oscillator
    recorded to a file can keep a cubic term that explains more than SIGNIFICANT."""
    import pysindy as ps

    t0 = time.perf_counter()
    v_s = _velocity_scale(motions)
    names = ["y", "v", "u", *LIBRARY]
    funcs = [lambda y, v, u: y, lambda y, v, u: v, lambda y, v, u: u, lambda y, v, u: y ** 3,
             lambda y, v, u: np.tanh(v / v_s), lambda y, v, u: v * np.abs(v)]
    library = ps.CustomLibrary(library_functions=funcs, function_names=[lambda *a, n=n: n for n in names])
    model = ps.SINDy(optimizer=ps.STLSQ(threshold=threshold, normalize_columns=True), feature_library=library)
    xs = [np.column_stack([m.y, m.v]) for m in motions]
    model.fit(xs, t=1.0 / motions[0].fs, x_dot=[np.column_stack([m.v, m.a]) for m in motions],
              u=[m.u[:, None] for m in motions])
    coef = model.coefficients()[1]  # the v equation
    theta = np.concatenate([np.column_stack([f(m.y, m.v, m.u) for f in funcs]) for m in motions])
    a = np.concatenate([m.a for m in motions])
    kept = {name: theta[:, j] for j, name in enumerate(LIBRARY, start=3) if coef[j] != 0.0}
    shares, chosen = _stepwise(list(kept), lambda names: _unexplained(
        np.column_stack([theta[:, :3], *(kept[n] for n in names)]), a))
    return _verdict("SINDy (pysindy)", shares, chosen, t0)


def narmax(motions: list[Motion], lags: int = 2) -> Named:
    """sysidentpy FROLS: a polynomial NARX model of degree 3 (lags of y and u up to `lags`), terms chosen by
    the error-reduction ratio and the number of terms by AIC, on the file of the highest force level; the
    chosen terms that are products of three output lags stand for cubic stiffness, their ERR over what the
    chosen linear terms leave as share.
    The polynomial basis holds no friction or |v|v term."""
    from sysidentpy.basis_function import Polynomial
    from sysidentpy.model_structure_selection import FROLS
    from sysidentpy.parameter_estimation import LeastSquares

    t0 = time.perf_counter()
    m = max(motions, key=lambda q: np.std(q.u))
    scale_y, scale_u = np.std(m.y), np.std(m.u)
    model = FROLS(order_selection=True, n_info_values=12, ylag=lags, xlag=lags, info_criteria="aic",
                  estimator=LeastSquares(), basis_function=Polynomial(degree=3))
    model.fit(X=(m.u / scale_u)[:, None], y=(m.y / scale_y)[:, None])
    chosen = list(zip(model.final_model, model.err))
    linear = sum(float(e) for code, e in chosen if np.count_nonzero(code) == 1)
    cubic = [float(e) for code, e in chosen if np.count_nonzero(code) == 3 and all(1000 <= c < 2000 for c in code)]
    # ERR is a share of the output's variance: as a share of what the linear terms leave
    shares = {"y^3": sum(cubic) / max(1.0 - linear, 1e-12)} if cubic else {}
    return _verdict("NARMAX (sysidentpy FROLS)", shares, [n for n, v in shares.items() if v >= SIGNIFICANT], t0,
                    note="polynomial basis: no friction or v|v| term")


METHODS = {"restoring-force surface": restoring_force, "SINDy (pysindy)": sindy,
           "NARMAX (sysidentpy FROLS)": narmax}


DIAGNOSE = "stockbridge diagnose"


@dataclass
class CaseVerdicts:
    """One validation-campaign case: what was withheld ('none', an effect, or 'a+b'), the weakest withheld effect's
    own size over the sensor noise (None on a null case), and what each method named ('none': nothing), the
    diagnosis's as its campaign run stored it."""

    case: str
    withheld: str
    weakest: float | None
    named: dict


def on_campaign(folder: pathlib.Path) -> list[CaseVerdicts]:
    """Every SDOF case of a validation campaign's folder (`stockbridge diagnose --campaign N --out FOLDER`) whose
    diagnosis ran: the equation-error methods (METHODS) on its data files, beside the diagnosis's verdict in its
    outcome.json."""
    out = []
    for done in sorted(pathlib.Path(folder).glob("case*/outcome.json")):
        o = json.loads(done.read_text(encoding="utf-8"))
        if o["named"] == "error" or o["case"]["model"] != "sdof":
            continue
        motions = read_motions(done.parent / "data")
        named = {DIAGNOSE: o["named"], **{m: fn(motions).effect or "none" for m, fn in METHODS.items()}}
        sizes = o.get("member_to_noise") or {}
        out.append(CaseVerdicts(done.parent.name, o["withheld"], min(sizes.values()) if sizes else None, named))
    return out


def _hits(cases: list[CaseVerdicts], method: str) -> str:
    right = sum(c.named[method] == c.withheld for c in cases)
    return f"{right}/{len(cases)} ({100 * right / len(cases):.0f} %)" if cases else "—"


def campaign_tables(cases: list[CaseVerdicts], detectable: float = 2.0) -> list[tuple[str, list[str], list]]:
    """(title, header, rows) of the campaign comparison: each method's top-1 accuracy (exactly what was withheld)
    on the effect cases, the single effects, the pairs and the cases whose weakest effect is at least `detectable`
    times the noise, with its false alarms on the null cases; then the hits by what was withheld."""
    methods = list(cases[0].named) if cases else []
    effects = [c for c in cases if c.withheld != "none"]
    nulls = [c for c in cases if c.withheld == "none"]
    singles = [c for c in effects if "+" not in c.withheld]
    pairs = [c for c in effects if "+" in c.withheld]
    strong = [c for c in effects if c.weakest is not None and c.weakest >= detectable]
    first = [[m, _hits(effects, m), _hits(singles, m), _hits(pairs, m), _hits(strong, m),
              f"{sum(c.named[m] != 'none' for c in nulls)}/{len(nulls)}"] for m in methods]
    kinds = sorted({c.withheld for c in singles}) + (["pairs"] if pairs else [])
    second = [[k, *[_hits(pairs if k == "pairs" else [c for c in singles if c.withheld == k], m) for m in methods]]
              for k in kinds]
    return [("Top-1 accuracy (exactly what was withheld) and false alarms",
             ["method", "effect cases", "single effects", "pairs", f"weakest effect ≥ {detectable:g} × the noise",
              "false alarms on null cases"], first),
            ("Named right, by what was withheld", ["withheld", *methods], second)]
