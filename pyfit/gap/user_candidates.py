"""Candidate effects a user declares without touching pyfit: a TOML file naming the FMU that holds the nominal
model and the new element(s) (built with `stockbridge build --with DIR My.Model`), and per candidate its FMU
parameters with bounds and a start rule. The diagnosis screens, refits and ranks them like the built-in ones.

    fmu = "my_fmus/SDOFMaxwell.fmu"     # relative to this file; default: the family's own FMU
    [[candidate]]
    name = "maxwell_damping"
    signature = "stiffness and damping that change with frequency, the same at every level"
    fixed = {}                          # FMU parameters set while the candidate is on
    linear = false                      # a change of the linear system (tells no gap below the noise threshold)
    [[candidate.parameter]]
    name = "k_m"                        # an FMU parameter; 0 must switch the element off for a strength
    lower = 0.0
    start = "0.05 * k"                  # a number [SI] or an expression in k, sigma_y, sigma_v, stuck_force
    upper = "2 * k"
    shape = false                       # a shape parameter is not charged in the score (default false)
    log = false                         # fitted on a log scale (positive, spanning decades)

k is the nominal model's stiffness [N/m], sigma_y and sigma_v the RMS of the nonlinear element's deflection [m]
and rate [m/s] simulated by the calibrated nominal model, stuck_force the force [N] a damper joint transmits when
it does not slip (the heavier end mass at the clamp's peak acceleration; 0 for the SDOF) (pyfit.gap.effect.Scale).
"""
from __future__ import annotations

import ast
import operator
import pathlib
from dataclasses import dataclass

from pyfit.gap.effect import Effect, Param, Scale
from pyfit.io.schema import ConfigError, check_sections, check_table, fail, read_toml

NAMES = ("k", "sigma_y", "sigma_v", "stuck_force")
_OPS = {ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: operator.mul, ast.Div: operator.truediv,
        ast.Pow: operator.pow}


class CandidateError(ConfigError):
    """A candidates file that cannot be used (the message names the file and the key)."""


@dataclass(frozen=True)
class Rule:
    """A bound or start: a number or an arithmetic expression in k, sigma_y, sigma_v and stuck_force (SI)."""

    text: str

    def __call__(self, scale: Scale) -> float:
        values = {"k": scale.k, "sigma_y": scale.sigma_y, "sigma_v": scale.sigma_v, "stuck_force": scale.stuck_force}

        def ev(node):
            if isinstance(node, ast.Expression):
                return ev(node.body)
            if isinstance(node, ast.Constant) and isinstance(node.value, (int, float)):
                return float(node.value)
            if isinstance(node, ast.Name):
                return values[node.id]
            if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub):
                return -ev(node.operand)
            return _OPS[type(node.op)](ev(node.left), ev(node.right))

        return float(ev(ast.parse(self.text, mode="eval")))


def _rule(value, path, where) -> Rule:
    """A checked Rule from a TOML number or string."""
    if isinstance(value, bool) or not isinstance(value, (int, float, str)):
        fail(path, where, f"must be a number or an expression, not {value!r}", error=CandidateError)
    text = str(value)
    try:
        tree = ast.parse(text, mode="eval")
    except SyntaxError:
        fail(path, where, f"'{text}' is not an expression", f"numbers, + - * / ** and {', '.join(NAMES)}",
             CandidateError)
    for node in ast.walk(tree):
        ok = isinstance(node, (ast.Expression, ast.Constant, ast.BinOp, ast.UnaryOp, ast.Load,
                               *(_OPS.keys()), ast.USub)) and not (isinstance(node, ast.Constant) and
                                                                 not isinstance(node.value, (int, float)))
        if isinstance(node, ast.Name):
            ok = node.id in NAMES
        if not ok:
            fail(path, where, f"'{text}' uses something else than numbers, + - * / ** and {', '.join(NAMES)}",
                 error=CandidateError)
    return Rule(text)


@dataclass(frozen=True)
class UserCandidates:
    """The effects declared in a candidates file and the FMU that holds them (None: the family's own)."""

    path: pathlib.Path
    fmu: pathlib.Path | None
    effects: dict  # name -> Effect

    @property
    def text(self) -> str:
        """The file's text (part of a diagnosis's key: a changed declaration refits)."""
        return self.path.read_text(encoding="utf-8")


_CANDIDATE = {"name": (str, True, None), "signature": (str, False, ""), "fixed": (dict, False, {}),
              "linear": (bool, False, False), "parameter": (list, True, None)}
_PARAMETER = {"name": (str, True, None), "lower": (object, True, None), "start": (object, True, None),
              "upper": (object, True, None), "shape": (bool, False, False), "log": (bool, False, False)}


def load(path) -> UserCandidates:
    """The candidates declared in a TOML file; one clear error per problem (file, key, what is allowed)."""
    path = pathlib.Path(path)
    raw = read_toml(path, CandidateError)
    check_sections(raw, path, ("fmu", "candidate"), required=("candidate",), error=CandidateError)
    fmu = None
    if "fmu" in raw:
        fmu = (path.parent / str(raw["fmu"])).resolve()
        if not fmu.is_file():
            fail(path, "fmu", f"{fmu} not found", "an FMU built with `stockbridge build --with DIR My.Model`",
                 CandidateError)
    effects = {}
    for i, entry in enumerate(raw["candidate"] if isinstance(raw["candidate"], list) else [raw["candidate"]]):
        c = check_table(entry, path, f"candidate[{i}]", _CANDIDATE, CandidateError)
        bad = [k for k, v in c["fixed"].items() if isinstance(v, bool) or not isinstance(v, (int, float))]
        if bad:
            fail(path, f"candidate[{i}].fixed.{bad[0]}", f"must be a number, not {c['fixed'][bad[0]]!r}",
                 error=CandidateError)
        params = []
        for j, p in enumerate(c["parameter"]):
            where = f"candidate[{i}].parameter[{j}]"
            q = check_table(p, path, where, _PARAMETER, CandidateError)
            lo, st, hi = (_rule(q[k], path, f"{where}.{k}") for k in ("lower", "start", "upper"))
            params.append(Param(q["name"], _Range(lo, st, hi), shape=q["shape"], log=q["log"]))
        if not any(not p.shape for p in params):
            fail(path, f"candidate[{i}].parameter", "no strength parameter (every one has shape = true)",
                 "at least one parameter whose zero switches the effect off", CandidateError)
        effects[c["name"]] = Effect(c["name"], tuple(params), fixed=_Fixed(dict(c["fixed"])),
                                    signature=c["signature"], linear=c["linear"])
    return UserCandidates(path, fmu, effects)


@dataclass(frozen=True)
class _Range:
    lower: Rule
    start: Rule
    upper: Rule

    def __call__(self, scale: Scale) -> tuple[float, float, float]:
        return self.lower(scale), self.start(scale), self.upper(scale)


@dataclass(frozen=True)
class _Fixed:
    values: dict

    def __call__(self, scale: Scale) -> dict:
        return dict(self.values)
