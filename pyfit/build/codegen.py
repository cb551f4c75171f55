"""Explicit model -> C sources (CasADi code generator) and the FMI 2.0 and 3.0 modelDescription.xml."""
from __future__ import annotations

import hashlib
import math
import re
import pathlib
import uuid
import xml.etree.ElementTree as ET
from dataclasses import dataclass

import casadi as ca

from pyfit.build.reduce import ExplicitModel

CS_STEP_NAME = "cs_step"
CS_STEP_DESCRIPTION = ("Co-simulation only: fixed Runge-Kutta 4 sub-step in s; 0 selects the adaptive "
                       "Dormand-Prince 5(4) solver with the tolerance of fmi2SetupExperiment")


@dataclass
class FmuVariable:
    """One ScalarVariable of the FMU; value reference = position in the wrapper's value array."""

    name: str
    vr: int
    type: str  # 'Real', 'Integer'
    causality: str
    variability: str
    initial: str | None
    start: float | None
    unit: str
    description: str
    settable: int  # 0 no, 1 parameter (before init), 2 input, 3 state start value (before init)
    derivative_of: int | None = None  # vr of the state
    minimum: float = float("-inf")
    maximum: float = float("inf")
    nominal: float | None = None


def layout(model: ExplicitModel) -> list[FmuVariable]:
    """All FMU variables in value-reference order (the wrapper's array layout)."""
    out: list[FmuVariable] = []

    def add(v, causality, variability, initial, start, settable, vtype="Real", name=None, unit=None, desc=None):
        out.append(FmuVariable(name or v.name, len(out), vtype, causality, variability, initial, start,
                               unit if unit is not None else v.unit,
                               desc if desc is not None else v.description, settable,
                               minimum=v.minimum if name is None else float("-inf"),
                               maximum=v.maximum if name is None else float("inf")))

    for v in model.parameters:
        vtype = "Integer" if v.python_type is int else "Real"
        add(v, "parameter", "fixed", "exact", float(v.value), 1, vtype)
    out.append(FmuVariable(CS_STEP_NAME, len(out), "Real", "parameter", "fixed", "exact", 0.0, "s",
                           CS_STEP_DESCRIPTION, 1))
    for v in model.calculated:
        vtype = "Integer" if v.python_type is int else "Real"
        add(v, "calculatedParameter", "fixed", "calculated", None, 0, vtype)
    for v in model.inputs:
        add(v, "input", "continuous", None, v.start, 2)
    first_state = len(out)
    for v in model.states:
        add(v, "local", "continuous", "exact", v.start, 3)
        out[-1].nominal = v.nominal
    for k, v in enumerate(model.states):
        unit = _derivative_unit(v.unit)
        add(v, "local", "continuous", "calculated", None, 0, name=f"der({v.name})", unit=unit,
            desc=f"Time derivative of {v.name}")
        out[-1].derivative_of = first_state + k
    for v in model.variables:
        add(v, "output" if v.is_output else "local", "continuous", "calculated", None, 0)
    return out


def _derivative_unit(unit: str) -> str:
    return {"m": "m/s", "m/s": "m/s2", "rad": "rad/s", "rad/s": "rad/s2", "N": "N/s"}.get(unit, "")


SAMPLED_SWITCH = "exc_type"  # the built-in excitation selector; 0 = inputs only (every run driven by data)
FAST_POW = """
/* pow with the exponents the models use most, exactly (x^1 = x, x^2 = x*x are correctly rounded) */
static inline double pyfit_pow(double x, double y) { return y == 1.0 ? x : y == 2.0 ? x * x : pow(x, y); }
"""


def casadi_functions(model: ExplicitModel, ident: str) -> list[ca.Function]:
    """The functions the wrapper calls, for each variant: ode, vars, jac and hoist, plus calc. `jac` is the
    forward-mode directional derivative d(xdot, vars) = J · s for a seed s over (states, inputs): its code grows
    like the model's, where a dense Jacobian's grows with (states + inputs) times it.

    Variant "" is the general model; variant "_s" (only for models with the parameter exc_type) has
    exc_type = 0 substituted, so a run driven by sampled inputs does not evaluate the built-in excitation's
    expressions. In each variant every subexpression that depends on parameters only is moved into the
    variant's `hoist` function (evaluated when a parameter changes, not at every right-hand side call) and
    enters ode/vars/jac as their fifth argument h.
    """
    args = [model.x, model.u, model.p, model.t]
    names = ["x", "u", "p", "t", "h"]
    allv = ca.vertcat(*model.variable_expr) if model.variable_expr else ca.SX(0, 1)
    calc = ca.Function(f"{ident}_calc", [model.p],
                       [ca.vertcat(*model.calculated_expr) if model.calculated_expr else ca.SX(0, 1)],
                       ["p"], ["c"])
    functions = [calc]
    pnames = [v.name for v in model.parameters]
    variants = {"": None}
    if SAMPLED_SWITCH in pnames:
        variants["_s"] = model.p[pnames.index(SAMPLED_SWITCH)]
    for suffix, switch in variants.items():
        xdot, var = (model.xdot, allv) if switch is None else (ca.substitute(e, switch, 0) for e in (model.xdot, allv))
        known = ca.vertcat(model.x, model.u)
        seed = ca.SX.sym("s", known.numel())
        jac = ca.jtimes(ca.vertcat(xdot, var), known, seed)
        (xdot, var, jac), symbols, parametric = ca.extract_parametric([xdot, var, jac], model.p)
        h = ca.vertcat(*symbols) if symbols else ca.SX(0, 1)
        functions += [ca.Function(f"{ident}_hoist{suffix}", [model.p],
                                  [ca.vertcat(*parametric) if parametric else ca.SX(0, 1)], ["p"], ["h"]),
                      ca.Function(f"{ident}_ode{suffix}", args + [h], [xdot], names, ["xdot"]),
                      ca.Function(f"{ident}_vars{suffix}", args + [h], [var], names, ["v"]),
                      ca.Function(f"{ident}_jac{suffix}", args + [h, seed], [jac], names + ["s"], ["dv"])]
    return functions


def state_aliases(model: ExplicitModel) -> list[int]:
    """For each variable (in the order of the vars function's output): the index over (inputs, states) of the input
    or state it equals, or -1 when it is computed. Such a variable is read from that input or state: an output that
    is a state (a displacement sensor on a mass) costs no evaluation of every variable at each communication point."""
    known = [model.u[i] for i in range(model.u.numel())] + [model.x[i] for i in range(model.x.numel())]
    return [next((k for k, s in enumerate(known) if ca.is_equal(e, s)), -1) if e.is_symbolic() else -1
            for e in model.variable_expr]


def write_sources(model: ExplicitModel, ident: str, guid: str, variables: list[FmuVariable],
                  folder: pathlib.Path) -> list[str]:
    """Write model_functions.c/.h and model_data.h into `folder`; return the C file names."""
    folder.mkdir(parents=True, exist_ok=True)
    gen = ca.CodeGenerator("model_functions.c", {"with_header": True})
    functions = casadi_functions(model, ident)
    for f in functions:
        gen.add(f)
    gen.generate(str(folder) + "/")
    code = (folder / "model_functions.c").read_text()
    head = code.index("#include <math.h>") + len("#include <math.h>")
    (folder / "model_functions.c").write_text(code[:head] + FAST_POW + re.sub(r"\bpow\(", "pyfit_pow(", code[head:]))
    n_hoist = max(f.nnz_out(0) for f in functions if "_hoist" in f.name())
    types = {"Real": 0, "Integer": 1}
    starts = [v.start if v.start is not None else 0.0 for v in variables]
    lines = [
        "/* Generated by pyfit's build from the Modelica sources: model sizes and start values. */",
        "#ifndef MODEL_DATA_H", "#define MODEL_DATA_H",
        f'#define MODEL_IDENTIFIER "{ident}"',
        f'#define MODEL_GUID "{guid}"',
        f"#define N_PARAMS {len(model.parameters) + 1}",
        f"#define N_CALC {len(model.calculated)}",
        f"#define N_INPUTS {len(model.inputs)}",
        f"#define N_STATES {len(model.states)}",
        f"#define N_VARS {len(model.variables)}",
        f"#define VR_CS_STEP {len(model.parameters)}",
    ]
    lines.append(f"#define N_HOIST {n_hoist}")
    sampled = SAMPLED_SWITCH in [v.name for v in model.parameters]
    lines.append(f"#define VR_SAMPLED_SWITCH {[v.name for v in model.parameters].index(SAMPLED_SWITCH) if sampled else -1}")
    for f in functions:
        key = f.name()[len(ident) + 1:].upper()
        lines.append(f"#define FUN_{key} {f.name()}")
        lines.append(f"#define FUN_{key}_work {f.name()}_work")
    nominals = [v.nominal or 1.0 for v in variables if v.settable == 3]
    lines.append("static const double STATE_NOMINALS[] = {" + ", ".join(repr(float(x)) for x in nominals or [1.0]) + "};")
    lines.append("static const double START_VALUES[] = {" + ", ".join(repr(float(s)) for s in starts) + "};")
    lines.append("static const int VAR_TYPE[] = {" + ", ".join(str(types[v.type]) for v in variables) + "};")
    lines.append("static const int VAR_SETTABLE[] = {" + ", ".join(str(v.settable) for v in variables) + "};")
    lines.append("static const int VAR_ALIAS[] = {" + ", ".join(str(k) for k in state_aliases(model) or [-1]) + "};")
    lines.append("#endif")
    (folder / "model_data.h").write_text("\n".join(lines) + "\n")
    return ["model_functions.c", "fmi2_wrapper.c"]


def guid_for(model: ExplicitModel, variables: list[FmuVariable]) -> str:
    """A GUID that changes whenever the interface or the equations change."""
    h = hashlib.sha256()
    h.update(model.name.encode())
    for v in variables:
        h.update(f"{v.name}|{v.type}|{v.causality}|{v.start}".encode())
    h.update(str(model.xdot).encode())
    return "{" + str(uuid.UUID(h.hexdigest()[:32])) + "}"


def _fmt(x: float) -> str:
    return repr(float(x)) if math.isfinite(x) else ("1e300" if x > 0 else "-1e300")


def _units_and_experiment(root: ET.Element, model: ExplicitModel, variables: list[FmuVariable]) -> None:
    units = sorted({v.unit for v in variables if v.unit})
    if units:
        ud = ET.SubElement(root, "UnitDefinitions")
        for u in units:
            ET.SubElement(ud, "Unit", {"name": u})
    exp = model.experiment
    if exp:
        attrs = {k: _fmt(exp[k2]) for k, k2 in (("startTime", "StartTime"), ("stopTime", "StopTime"),
                                                 ("tolerance", "Tolerance"), ("stepSize", "Interval")) if k2 in exp}
        ET.SubElement(root, "DefaultExperiment", attrs)


def _variable_attributes(v: FmuVariable) -> dict[str, str]:
    """The attributes FMI 2.0 and 3.0 share: name, value reference, causality, variability, description, initial."""
    attrs = {"name": v.name, "valueReference": str(v.vr), "causality": v.causality, "variability": v.variability}
    if v.description:
        attrs["description"] = v.description
    if v.initial:
        attrs["initial"] = v.initial
    return attrs


def _bounds_and_start(v: FmuVariable) -> dict[str, str]:
    attrs = {}
    if v.nominal:
        attrs["nominal"] = _fmt(v.nominal)
    for key, bound in (("min", v.minimum), ("max", v.maximum)):
        if math.isfinite(bound):
            attrs[key] = str(int(bound)) if v.type == "Integer" else _fmt(bound)
    if v.start is not None:
        attrs["start"] = str(int(v.start)) if v.type == "Integer" else _fmt(v.start)
    return attrs


def _xml(root: ET.Element) -> bytes:
    ET.indent(root)
    return b'<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="utf-8")


def model_description(model: ExplicitModel, ident: str, guid: str, variables: list[FmuVariable],
                      sources: list[str]) -> bytes:
    """The FMI 2.0 modelDescription.xml for an FMU with both Model Exchange and Co-Simulation."""
    root = ET.Element("fmiModelDescription", {
        "fmiVersion": "2.0", "modelName": model.name, "guid": guid,
        "description": model.description or model.name,
        "generationTool": "pyfit build (pymoca front end, CasADi code generator)",
        "variableNamingConvention": "structured", "numberOfEventIndicators": "0"})
    common = {"modelIdentifier": ident, "providesDirectionalDerivative": "true",
              "canGetAndSetFMUstate": "true", "canSerializeFMUstate": "true",
              "canNotUseMemoryManagementFunctions": "true"}
    me = ET.SubElement(root, "ModelExchange", dict(common, completedIntegratorStepNotNeeded="true"))
    cs = ET.SubElement(root, "CoSimulation", dict(common, canHandleVariableCommunicationStepSize="true",
                                                  canInterpolateInputs="true", maxOutputDerivativeOrder="0"))
    for el in (me, cs):
        sf = ET.SubElement(el, "SourceFiles")
        for s in sources:
            ET.SubElement(sf, "File", {"name": s})
    _units_and_experiment(root, model, variables)
    mv = ET.SubElement(root, "ModelVariables")
    for v in variables:
        attrs = _variable_attributes(v)
        sv = ET.SubElement(mv, "ScalarVariable", attrs)
        tattrs = {}
        if v.type == "Real":
            if v.unit:
                tattrs["unit"] = v.unit
            if v.derivative_of is not None:
                tattrs["derivative"] = str(v.derivative_of + 1)
        ET.SubElement(sv, v.type, dict(tattrs, **_bounds_and_start(v)))
    ms = ET.SubElement(root, "ModelStructure")
    outputs = [v for v in variables if v.causality == "output"]
    derivs = [v for v in variables if v.derivative_of is not None]
    if outputs:
        el = ET.SubElement(ms, "Outputs")
        for v in outputs:
            ET.SubElement(el, "Unknown", {"index": str(v.vr + 1)})
    if derivs:
        el = ET.SubElement(ms, "Derivatives")
        for v in derivs:
            ET.SubElement(el, "Unknown", {"index": str(v.vr + 1)})
    init = _initial_unknowns(variables)
    if init:
        el = ET.SubElement(ms, "InitialUnknowns")
        for v in init:
            ET.SubElement(el, "Unknown", {"index": str(v.vr + 1)})
    return _xml(root)


def _initial_unknowns(variables: list[FmuVariable]) -> list[FmuVariable]:
    return [v for v in variables if v.causality in ("output", "calculatedParameter") or v.derivative_of is not None]


FMI3_TYPES = {"Real": "Float64", "Integer": "Int32"}


def model_description_fmi3(model: ExplicitModel, ident: str, guid: str, variables: list[FmuVariable]) -> bytes:
    """The FMI 3.0 modelDescription.xml of the same variables (value references unchanged; `time`, the
    independent variable, is added after them), Model Exchange and Co-Simulation."""
    root = ET.Element("fmiModelDescription", {
        "fmiVersion": "3.0", "modelName": model.name, "instantiationToken": guid,
        "description": model.description or model.name,
        "generationTool": "pyfit build (pymoca front end, CasADi code generator)",
        "variableNamingConvention": "structured"})
    common = {"modelIdentifier": ident, "providesDirectionalDerivatives": "true",
              "canGetAndSetFMUState": "true", "canSerializeFMUState": "true"}
    ET.SubElement(root, "ModelExchange", dict(common, completedIntegratorStepNotNeeded="true"))
    ET.SubElement(root, "CoSimulation", dict(common, canHandleVariableCommunicationStepSize="true",
                                             maxOutputDerivativeOrder="0", hasEventMode="false"))
    _units_and_experiment(root, model, variables)
    mv = ET.SubElement(root, "ModelVariables")
    time_vr = len(variables)
    ET.SubElement(mv, "Float64", {"name": "time", "valueReference": str(time_vr), "causality": "independent",
                                  "variability": "continuous", "description": "Simulation time", "unit": "s"})
    for v in variables:
        attrs = _variable_attributes(v)
        if v.type == "Real" and v.unit:
            attrs["unit"] = v.unit
        if v.derivative_of is not None:
            attrs["derivative"] = str(v.derivative_of)
        ET.SubElement(mv, FMI3_TYPES[v.type], dict(attrs, **_bounds_and_start(v)))
    ms = ET.SubElement(root, "ModelStructure")
    for v in variables:
        if v.causality == "output":
            ET.SubElement(ms, "Output", {"valueReference": str(v.vr)})
    for v in variables:
        if v.derivative_of is not None:
            ET.SubElement(ms, "ContinuousStateDerivative", {"valueReference": str(v.vr)})
    for v in _initial_unknowns(variables):
        ET.SubElement(ms, "InitialUnknown", {"valueReference": str(v.vr)})
    return _xml(root)


def build_description_fmi3(ident: str, sources: list[str]) -> bytes:
    """sources/buildDescription.xml of the FMI 3.0 FMU: the C files to compile it from source."""
    root = ET.Element("fmiBuildDescription", {"fmiVersion": "3.0"})
    conf = ET.SubElement(root, "BuildConfiguration", {"modelIdentifier": ident})
    files = ET.SubElement(conf, "SourceFileSet", {"language": "C99"})
    for s in sources:
        ET.SubElement(files, "SourceFile", {"name": s})
    return _xml(root)
