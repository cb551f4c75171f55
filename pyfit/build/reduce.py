"""Acausal flat model -> explicit ODE  dx/dt = f(x, u, p, t)  plus explicit expressions for every variable.

pymoca does no index reduction, so connections leave aliases and constraints between states
(two masses rigidly joined, a node whose motion a shaker prescribes). The reduction here:

1. eliminates every equation that is affine in exactly one unknown (unknowns are the derivatives
   of states and the algebraic variables), and pure aliases a = +-b between two unknowns;
2. treats an equation left with no unknown as a constraint g(x, u, t) = 0 between states: one state in
   it is demoted to an algebraic variable (determined by g) and the differentiated
   constraint dg/dt = 0 is added (derivatives of inputs come from the model's __pyfit(inputDerivatives)
   annotation, derivatives of time functions are exact). pymoca does not read StateSelect, so the
   choice is: demote a state whose derivative is not a state (a relative coordinate) before the
   position of a mass, and among equals the last declared;
3. repeats 1-2 until neither applies, then solves the remaining coupled equations block by block
   (block lower triangular order); each block must be affine in its unknowns.

Everything is symbolic (CasADi SX), so the result is exact and can be differentiated.
"""
from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from pyfit.build.frontend import FlatModel, ModelicaError, Variable


@dataclass
class ExplicitModel:
    """Explicit ODE form of a Modelica model; every expression is in terms of (x, u, p, t) symbols."""

    name: str
    description: str
    states: list[Variable]  # kept states, in declaration order
    inputs: list[Variable]
    parameters: list[Variable]  # independent (settable) parameters with numeric start values
    calculated: list[Variable]  # parameters computed from other parameters
    calculated_expr: list[ca.SX]  # in terms of the independent parameters
    x: ca.SX
    u: ca.SX
    p: ca.SX
    t: ca.SX
    xdot: ca.SX
    variables: list[Variable]  # every other variable (outputs, algebraics, demoted states)
    variable_expr: list[ca.SX]
    demoted: list[str]
    experiment: dict
    input_derivatives: dict


def _is_zero(e: ca.SX) -> bool:
    return e.is_constant() and float(ca.evalf(e)) == 0.0


class _Reducer:
    def __init__(self, flat: FlatModel):
        self.flat = flat
        self.by_name: dict[str, Variable] = {v.name: v for v in flat.variables}
        mx_syms, sx_syms, self.names = [], [], []
        for v in flat.variables:
            mx_syms.append(v.symbol)
            sx_syms.append(ca.SX.sym(v.name))
            self.names.append(v.name)
        self.der_name = {s: f"der({s})" for s in flat.der_symbols}
        for s, d in flat.der_symbols.items():
            mx_syms.append(d)
            sx_syms.append(ca.SX.sym(self.der_name[s]))
            self.names.append(self.der_name[s])
        mx_syms.append(flat.time)
        self.t = ca.SX.sym("time")
        sx_syms.append(self.t)
        self.names.append("time")
        self.sym = dict(zip(self.names, sx_syms))

        to_sx = ca.Function("to_sx", mx_syms, flat.equations, {"allow_free": True})
        self.eqs: list[ca.SX] = to_sx.call(sx_syms) if flat.equations else []
        # parameter values (numbers or expressions of other parameters) in SX
        self.param_value: dict[str, object] = {}
        for v in flat.variables:
            if v.kind in ("parameter", "constant"):
                if isinstance(v.value, ca.MX):
                    f = ca.Function("pv", mx_syms, [v.value], {"allow_free": True})
                    self.param_value[v.name] = f(*sx_syms)
                else:
                    self.param_value[v.name] = float(v.value if v.value is not None else 0.0)

        self.states = [v.name for v in flat.variables if v.kind == "state"]
        self.unknown = {v.name for v in flat.variables if v.kind == "algebraic"} | set(self.der_name.values())
        self.solution: dict[str, ca.SX] = {}  # eliminated unknown -> expression (in remaining unknowns/knowns)
        self.order: list[str] = []
        self.demoted: list[str] = []
        self._substitute_constants()

    # ---- helpers -------------------------------------------------------------------------------
    def _substitute_constants(self):
        names = [n for n, v in self.by_name.items() if v.kind == "constant" and isinstance(self.param_value[n], float)]
        if names:
            syms = [self.sym[n] for n in names]
            vals = [ca.SX(self.param_value[n]) for n in names]
            self.eqs = list(ca.substitute(self.eqs, syms, vals))

    def _names_in(self, e: ca.SX) -> set[str]:
        return {s.name() for s in ca.symvar(e)}

    def _eliminate(self, var: str, expr: ca.SX):
        s = self.sym[var]
        self.eqs = list(ca.substitute(self.eqs, [s], [expr])) if self.eqs else []
        keys = list(self.solution)
        if keys:
            vals = ca.substitute([self.solution[k] for k in keys], [s], [expr])
            self.solution = dict(zip(keys, vals))
        self.solution[var] = expr
        self.order.append(var)
        self.unknown.discard(var)

    def _d_dt(self, g: ca.SX) -> ca.SX:
        """Total time derivative of an expression of states, inputs, parameters and time."""
        out = ca.jacobian(g, self.t)
        for n in sorted(self._names_in(g)):  # sorted: the same expression (and GUID) in every process
            if n == "time":
                continue
            v = self.by_name.get(n)
            if v is None or v.kind in ("parameter", "constant"):
                continue
            dg = ca.jacobian(g, self.sym[n])
            if v.kind == "state":
                d = self.der_name[n]
                rate = self.solution.get(d, self.sym[d])
            elif v.kind == "input":
                if n not in self.flat.input_derivatives:
                    raise ModelicaError(
                        f"{self.flat.name}: a constraint needs the time derivative of input '{n}'; declare it with "
                        f"annotation(__pyfit(inputDerivatives=\"{n}:<input holding d{n}/dt>\"))")
                rate = self.sym[self.flat.input_derivatives[n]]
            else:
                raise ModelicaError(f"{self.flat.name}: cannot differentiate constraint containing '{n}'")
            out = out + dg * rate
        return ca.simplify(out)

    # ---- the reduction loop --------------------------------------------------------------------
    def _try_eliminate(self) -> bool:
        for i, e in enumerate(self.eqs):
            unk = self._names_in(e) & self.unknown
            if len(unk) == 1:
                (var,) = unk
                s = self.sym[var]
                coef = ca.jacobian(e, s)
                if ca.depends_on(coef, s):
                    continue  # not affine in it; left for the block solver (which will report it)
                if _is_zero(coef):
                    continue
                rest = ca.substitute(e, s, ca.SX(0))
                expr = ca.simplify(-rest / coef)
                del self.eqs[i]
                self._eliminate(var, expr)
                return True
            if len(unk) == 2:
                a, b = sorted(unk, key=self._elimination_rank)
                sa, sb = self.sym[a], self.sym[b]
                ca_, cb_ = ca.jacobian(e, sa), ca.jacobian(e, sb)
                if not (ca_.is_constant() and cb_.is_constant()):
                    continue
                rest = ca.substitute(e, ca.vertcat(sa, sb), ca.vertcat(ca.SX(0), ca.SX(0)))
                if not _is_zero(rest) or _is_zero(ca_):
                    continue
                del self.eqs[i]
                self._eliminate(a, ca.simplify(-cb_ * sb / ca_))
                return True
        return False

    def _elimination_rank(self, name: str):
        # eliminate plain algebraic variables before state derivatives, deeper (more local) names first
        return (name.startswith("der("), -name.count("."), name)

    def _keep_priority(self, state: str) -> int:
        """1 if der(state) is another kept state (a position whose velocity is a state), else 0."""
        d = self.solution.get(self.der_name[state])
        return int(d is not None and d.is_symbolic() and d.name() in self.states)

    def _try_constraint(self) -> bool:
        for i, e in enumerate(self.eqs):
            names = self._names_in(e)
            if names & self.unknown:
                continue
            states = [n for n in self.states if n in names]
            if not states:
                raise ModelicaError(
                    f"{self.flat.name}: equation '{e}' involves no unknown: the model is overdetermined")
            # demote a state that the constraint can determine (affine, non-zero): first one whose derivative
            # is not itself a state (a relative coordinate rather than a mass's position), last declared first
            for var in sorted(reversed(states), key=self._keep_priority):
                coef = ca.jacobian(e, self.sym[var])
                if not _is_zero(coef) and not ca.depends_on(coef, self.sym[var]):
                    break
            else:
                raise ModelicaError(f"{self.flat.name}: constraint '{e}' cannot be solved for any of its states")
            dg = self._d_dt(e)
            self.states.remove(var)
            self.demoted.append(var)
            self.unknown.add(var)
            d = self.der_name[var]
            if d not in self.solution:
                # der(var) is no longer a state derivative: it is an algebraic (dummy) derivative
                self.unknown.add(d)
            self.eqs.append(dg)
            return True
        return False

    def run(self):
        if len(self.eqs) != len(self.unknown):
            raise ModelicaError(
                f"{self.flat.name}: the model is not balanced: {len(self.eqs)} equations for {len(self.unknown)} "
                f"unknowns (state derivatives and algebraic variables)")
        while self._try_eliminate() or self._try_constraint():
            pass
        self._solve_blocks()

    def _solve_blocks(self):
        eqs = self.eqs
        unknowns = sorted(self.unknown)
        if len(eqs) != len(unknowns):
            raise ModelicaError(
                f"{self.flat.name}: {len(eqs)} equations for {len(unknowns)} unknowns after reduction "
                f"(unknowns: {', '.join(unknowns[:20])})")
        if not eqs:
            return
        inc = [[j for j, u in enumerate(unknowns) if u in self._names_in(e)] for e in eqs]
        match = _matching(inc, len(unknowns))
        if match is None:
            raise ModelicaError(f"{self.flat.name}: the remaining equations are structurally singular "
                                f"(unknowns: {', '.join(unknowns)})")
        var_of_eq = match  # eq index -> var index
        eq_of_var = {v: e for e, v in enumerate(var_of_eq)}
        # dependency graph on equations: eq i depends on eq_of_var[j] for every other unknown j it contains
        graph = {i: [eq_of_var[j] for j in inc[i] if j != var_of_eq[i]] for i in range(len(eqs))}
        for block in _tarjan(graph):  # dependencies first
            vars_ = [unknowns[var_of_eq[i]] for i in block]
            syms = ca.vertcat(*[self.sym[v] for v in vars_])
            F = ca.vertcat(*[self.eqs[i] for i in block])
            J = ca.jacobian(F, syms)
            if ca.depends_on(J, syms):
                raise ModelicaError(f"{self.flat.name}: nonlinear algebraic loop in {vars_}; only loops affine "
                                    f"in their unknowns are supported")
            b = -ca.substitute(F, syms, ca.SX.zeros(syms.shape))
            sol = ca.solve(J, b) if len(block) > 1 else b / J
            for k, v in enumerate(vars_):
                self._eliminate(v, ca.simplify(sol[k]))
                sol = ca.substitute(sol, self.sym[v], self.solution[v])
        self.eqs = []

    def result(self) -> ExplicitModel:
        flat = self.flat
        kept = [self.by_name[n] for n in self.states]
        inputs = [v for v in flat.variables if v.kind == "input"]
        params = [v for v in flat.variables if v.kind == "parameter"]
        independent = [v for v in params if isinstance(self.param_value[v.name], float)]
        calculated = [v for v in params if not isinstance(self.param_value[v.name], float)]
        x = ca.vertcat(*[self.sym[v.name] for v in kept]) if kept else ca.SX(0, 1)
        u = ca.vertcat(*[self.sym[v.name] for v in inputs]) if inputs else ca.SX(0, 1)
        p = ca.vertcat(*[self.sym[v.name] for v in independent]) if independent else ca.SX(0, 1)
        # dependent parameters in terms of independent ones (resolve chains by repeated substitution)
        calc_syms = [self.sym[v.name] for v in calculated]
        calc_expr = [self.param_value[v.name] for v in calculated]
        for _ in range(len(calculated) + 1):
            if not calc_syms or not any(ca.depends_on(e, ca.vertcat(*calc_syms)) for e in calc_expr):
                break
            calc_expr = list(ca.substitute(calc_expr, calc_syms, calc_expr))
        else:
            raise ModelicaError(f"{flat.name}: parameter bindings are cyclic")

        def in_xupt(exprs):
            if not exprs:
                return []
            exprs = list(ca.substitute(exprs, calc_syms, calc_expr)) if calc_syms else list(exprs)
            const = [n for n, v in self.by_name.items() if v.kind == "constant"]
            if const:
                exprs = list(ca.substitute(exprs, [self.sym[n] for n in const],
                                           [ca.SX(self.param_value[n]) if isinstance(self.param_value[n], float)
                                            else self.param_value[n] for n in const]))
            return exprs

        xdot = []
        for v in kept:
            d = self.der_name[v.name]
            if d not in self.solution:
                raise ModelicaError(f"{flat.name}: no equation determines der({v.name})")
            xdot.append(self.solution[d])
        xdot = in_xupt(xdot)
        others = [v for v in flat.variables if v.kind in ("algebraic",) or v.name in self.demoted]
        for v in others:
            if v.name not in self.solution:
                raise ModelicaError(f"{flat.name}: variable '{v.name}' is not determined by the equations")
        var_expr = in_xupt([self.solution[v.name] for v in others])
        allowed = ca.vertcat(x, u, p, self.t)
        for e, v in zip(xdot + var_expr, kept + others):
            free = {s.name() for s in ca.symvar(e)} - {s.name() for s in ca.symvar(allowed)}
            if free:
                raise ModelicaError(f"{flat.name}: expression of '{v.name}' still contains {sorted(free)}")
        return ExplicitModel(
            name=flat.name, description=flat.description, states=kept, inputs=inputs, parameters=independent,
            calculated=calculated, calculated_expr=calc_expr, x=x, u=u, p=p, t=self.t,
            xdot=ca.vertcat(*xdot) if xdot else ca.SX(0, 1), variables=others,
            variable_expr=var_expr, demoted=list(self.demoted), experiment=flat.experiment,
            input_derivatives=flat.input_derivatives)


def _matching(inc: list[list[int]], nvars: int):
    """Maximum bipartite matching equations -> variables (augmenting paths); None if not perfect."""
    var_to_eq = [-1] * nvars

    def augment(i, seen):
        for j in inc[i]:
            if j in seen:
                continue
            seen.add(j)
            if var_to_eq[j] < 0 or augment(var_to_eq[j], seen):
                var_to_eq[j] = i
                return True
        return False

    for i in range(len(inc)):
        if not augment(i, set()):
            return None
    eq_to_var = [-1] * len(inc)
    for j, i in enumerate(var_to_eq):
        if i >= 0:
            eq_to_var[i] = j
    return eq_to_var


def _tarjan(graph: dict[int, list[int]]) -> list[list[int]]:
    """Strongly connected components, each listed after the components it depends on."""
    index, low, on_stack, stack, out = {}, {}, set(), [], []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on_stack.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.append(w)
                if w == v:
                    break
            out.append(comp)

    for v in graph:
        if v not in index:
            visit(v)
    return out


def reduce_model(flat: FlatModel) -> ExplicitModel:
    """Index-reduce and causalise a flattened model into explicit ODE form."""
    r = _Reducer(flat)
    r.run()
    return r.result()
