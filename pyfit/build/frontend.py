"""Modelica front end: parse the library, flatten one model with pymoca, collect its metadata.

The .mo files are the single source of truth; this module only reads them.
"""
from __future__ import annotations

import pathlib
import re
from dataclasses import dataclass, field

import casadi as ca

# pymoca 0.12 calls MX.__div__ for Modelica '/', which casadi 3.8 no longer defines.
if not hasattr(ca.MX, "__div__"):
    ca.MX.__div__ = ca.MX.__truediv__

from pyfit.catalog import ModelicaError  # noqa: E402
from pymoca import parser as mo_parser  # noqa: E402
from pymoca import tree as mo_tree  # noqa: E402
from pymoca import ast as mo_ast  # noqa: E402
from pymoca.backends.casadi import generator as mo_generator  # noqa: E402


@dataclass
class Variable:
    """One scalar variable of the flattened model (SI units as declared in the .mo files)."""

    name: str
    kind: str  # 'state', 'algebraic', 'input', 'parameter', 'constant'
    symbol: ca.MX
    unit: str = ""
    description: str = ""
    start: float = 0.0
    value: object = None  # parameters/constants: float, or MX expression of other parameters
    python_type: type = float
    is_output: bool = False
    minimum: float = float("-inf")
    maximum: float = float("inf")
    nominal: float | None = None  # the declared nominal magnitude (states: the importer's error scale)


@dataclass
class FlatModel:
    """Flattened acausal model: residual equations F(...) = 0 over its variables."""

    name: str
    description: str
    variables: list[Variable]
    der_symbols: dict[str, ca.MX]  # state name -> MX symbol of der(state)
    equations: list[ca.MX]
    time: ca.MX
    experiment: dict[str, float] = field(default_factory=dict)
    input_derivatives: dict[str, str] = field(default_factory=dict)  # input -> input that is its derivative


def parse_library(library):
    """Parse every .mo file below `library` (a folder, or a list of folders: e.g. this library and yours)
    into one pymoca tree.

    A syntax error raises ModelicaError naming the file and the line.
    """
    files = []
    for folder in (library if isinstance(library, (list, tuple)) else [library]):
        found = sorted(pathlib.Path(folder).rglob("*.mo"))
        if not found:
            raise ModelicaError(f"{folder}: no .mo files found")
        files += found
    tree = None
    for path in files:
        try:
            parsed = mo_parser.parse(path.read_text(encoding="utf-8"))
        except Exception as exc:  # pymoca's ModelicaSyntaxError carries '(input, line N)'
            line = re.search(r"line (\d+)", str(exc))
            where = f"{path}:{line.group(1)}" if line else str(path)
            raise ModelicaError(f"{where}: Modelica syntax error: {exc}") from exc
        if parsed is None:
            raise ModelicaError(f"{path}: could not be parsed")
        if tree is None:
            tree = parsed
        else:
            tree.extend(parsed)
    return tree


def _annotation_to_dict(node):
    """Turn a pymoca annotation (ClassModification) into nested dicts of plain values."""
    if node is None:
        return {}
    args = getattr(node, "arguments", None)
    if args is None:
        value = getattr(node, "value", node)
        return getattr(value, "value", value)
    out = {}
    for arg in args:
        mod = arg.value
        mods = getattr(mod, "modifications", [])
        out[mod.component.name] = _annotation_to_dict(mods[0]) if mods else None
    return out


def _find_class(tree, dotted: str):
    node = tree
    for part in dotted.split("."):
        if part not in node.classes:
            raise ModelicaError(f"class '{dotted}' not found in the library (no '{part}')")
        node = node.classes[part]
    return node


def load(library, model_name: str) -> FlatModel:
    """Flatten `model_name` (for example 'StockbridgeDamper.Examples.SDOFBoucWen') from the library folder (or
    folders)."""
    tree = parse_library(library)
    original = _find_class(tree, model_name)
    annotation = _annotation_to_dict(original.annotation)
    try:
        flat = mo_tree.flatten(tree, mo_ast.ComponentRef.from_string(model_name))
        flat_class = list(flat.classes.values())[0]
        descriptions = {name: (sym.comment or "") for name, sym in flat_class.symbols.items()}
        protected = {name for name, sym in flat_class.symbols.items()
                     if str(getattr(sym, "visibility", "")).upper().endswith("PROTECTED")}
        model = _generate(flat, model_name)
    except Exception as exc:
        raise ModelicaError(f"{model_name}: pymoca could not flatten the model: {exc}") from exc
    outputs = set(model.outputs)
    variables: list[Variable] = []
    for kind, group in (("state", model.states), ("algebraic", model.alg_states), ("input", model.inputs),
                        ("parameter", model.parameters), ("constant", model.constants)):
        for v in group:
            name = v.symbol.name()
            start = v.start
            var_kind = kind
            if kind == "parameter" and name in protected and not isinstance(v.value, ca.MX):
                var_kind = "constant"  # a protected parameter with a literal value cannot be set
            variables.append(Variable(
                name=name, kind=var_kind, symbol=v.symbol, unit=getattr(v, "unit", "") or "",
                description=descriptions.get(name, ""),
                start=float(start) if isinstance(start, (int, float)) else 0.0,
                value=v.value, python_type=v.python_type, is_output=name in outputs,
                minimum=_bound(v, "min", float("-inf")), maximum=_bound(v, "max", float("inf")),
                nominal=_nominal(v)))
    der_symbols = {s.symbol.name(): d.symbol for s, d in zip(model.states, model.der_states)}
    if model.initial_equations:
        raise ModelicaError(f"{model_name}: initial equations are not supported; give start values")

    input_derivatives = {}
    pyfit_ann = annotation.get("__pyfit") or {}
    for pair in filter(None, str(pyfit_ann.get("inputDerivatives", "")).split(",")):
        if ":" not in pair:
            raise ModelicaError(
                f"{model_name}: annotation __pyfit(inputDerivatives) entry '{pair}' is not 'input:derivativeInput'")
        a, b = (p.strip() for p in pair.split(":"))
        input_derivatives[a] = b
    _fix_self_references(variables, model_name)
    equations = [e for e in model.equations if not (e.is_constant() and float(ca.evalf(e)) == 0.0)]
    experiment = {k: float(v) for k, v in (annotation.get("experiment") or {}).items()}
    return FlatModel(model_name, original.comment or "", variables, der_symbols, equations, model.time,
                     experiment, input_derivatives)


def _generate(flat, model_name: str):
    """pymoca's CasADi model of an already flattened tree (what pymoca's generate_model does after flattening
    it itself: flattening is most of a build's front-end time, so it is done once)."""
    options = mo_generator._merge_default_options({"check_balanced": False, "expand_vectors": True})
    generator = mo_generator.Generator(flat, model_name, options)
    mo_generator.GeneratorWalker().walk(generator, flat)
    model = generator.model
    model.simplify(options)
    model._post_checks()
    return model


def _bound(v, attr: str, default: float) -> float:
    """A numeric min/max attribute of a pymoca variable, or the default when absent or symbolic."""
    value = getattr(v, attr, None)
    return float(value) if isinstance(value, (int, float)) and not isinstance(value, bool) else default


def _nominal(v) -> float | None:
    """The declared nominal of a pymoca variable (pymoca: 0 when none is declared; aliases give the largest)."""
    value = getattr(v, "nominal", None)
    if isinstance(value, (ca.MX, ca.SX, ca.DM)):
        if isinstance(value, ca.DM) or value.is_constant():
            value = float(ca.evalf(value)) if not isinstance(value, ca.DM) else float(value)
        else:
            return None
    return float(value) if isinstance(value, (int, float)) and not isinstance(value, bool) and value > 0 else None


def _fix_self_references(variables: list[Variable], model_name: str) -> None:
    """Repair pymoca 0.12's scoping of modifiers such as `Mass mass(m=m)`.

    pymoca resolves the right-hand side in the component's own scope, so `mass.m` gets the value
    `mass.m`. Modelica resolves it in the enclosing scope: replace the value by the nearest
    enclosing parameter of the same name.
    """
    by_name = {v.name: v for v in variables}
    for v in variables:
        if isinstance(v.value, ca.MX) and v.value.is_symbolic() and v.value.name() == v.name:
            parts = v.name.split(".")
            for depth in range(len(parts) - 2, -1, -1):
                outer = ".".join(parts[:depth] + [parts[-1]])
                if outer in by_name and outer != v.name:
                    v.value = by_name[outer].symbol
                    break
            else:
                raise ModelicaError(f"{model_name}: parameter '{v.name}' is bound to itself")
