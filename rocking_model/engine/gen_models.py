"""Build step: the C kernels of every registered model, generated from its declaration.

Each model class declares its parameters, initial values and outputs (`rocking_model.params.Param`) and its
mechanics (``mechanics(sp, p, q, v)`` returning `rocking_model.models.declare.Mechanics`: kinetic energy,
first moment of mass, elastic energy, dissipation, contact points). From these this module derives, with
sympy, everything the engine asks of a model (`rk_model_ops` in src/rk_model.h):

- the full-coordinate system: M(q) (the Hessian of T in v), f(q, v, ag, ag_v) from Lagrange's equations, the
  stiff part (K, C: the Hessians of the elastic energy and of the dissipation, at the current state), gaps,
  contact Jacobians W_N, W_T, their drifts, the contacts' abscissae, the switches of the force laws;
- each sticking contact mode of the two-corner base (full contact, rocking on either corner, flight): its
  reduced coordinates and embedding, the reduced mass matrix Jᵀ M J and forces Jᵀ (f - M J̇ ṙ), the reduced
  acceleration (closed form for one or two coordinates and diagonal systems, else a small dense solve), the
  contact forces of its closed corners (the rows of M q̈ - f along the base's translations and rotation), and
  its event functions (forces of the closed corners over the force scale, gaps of the open ones over the
  length scale, the overturning margin); for a model whose forces depend on the base's horizontal position,
  all of it with the base at the offset ``m->offset`` from its rest position;
- outputs, energy, initial state, parameter tables and checks, derived constants.

Subexpressions of the parameters alone are computed once per model instance (``m->d[]``, at construction);
the rest is common-subexpression eliminated per function. The output, src/rk_models_gen.c, is written only
when its inputs changed (a hash of the declarations and of this file heads it).

Run: ``python -m rocking_model.engine.gen_models`` (setup.py runs it before compiling the engine).
"""
from __future__ import annotations

import hashlib
import importlib
import inspect
import math
import os
import re
import sys

import sympy as sp
from sympy.printing.c import C99CodePrinter

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "src", "rk_models_gen.c")

# the two-corner contact modes (rk_common.h) and the contacts each one closes
FULL, LEFT, RIGHT, FLIGHT = 0, 1, 2, 3
STICKING = (FULL, LEFT, RIGHT, FLIGHT)
CLOSED = {FULL: (0, 1), LEFT: (0,), RIGHT: (1,), FLIGHT: ()}
MODE_NAME = {FULL: "RK_MODE_FULL", LEFT: "RK_MODE_LEFT", RIGHT: "RK_MODE_RIGHT", FLIGHT: "RK_MODE_FLIGHT"}
MAX_DERIVED = 256       # RK_MAX_DERIVED
HALF_PI = sp.Symbol("RK_HALF_PI")


# ------------------------------------------------------------------------------------------------ printing
class _Printer(C99CodePrinter):
    """C99 with small integer powers as products (no libm pow) and symbols renamed for the kernel."""

    def __init__(self, names: dict):
        super().__init__()
        self._names = names

    def _print_Symbol(self, expr):
        return self._names.get(expr, expr.name)

    def _print_Pow(self, expr):
        base, ex = expr.base, expr.exp
        if ex.is_Integer and 1 < abs(int(ex)) <= 4:
            b = self.parenthesize(base, 50)
            prod = " * ".join([b] * abs(int(ex)))
            return f"({prod})" if ex > 0 else f"(1.0 / ({prod}))"
        if ex == -1:
            return f"(1.0 / {self.parenthesize(base, 50)})"
        if ex == sp.Rational(1, 2):
            return f"sqrt({self._print(base)})"
        if ex == -sp.Rational(1, 2):
            return f"(1.0 / sqrt({self._print(base)}))"
        return f"pow({self._print(base)}, {self._print(ex)})"

    def _print_Rational(self, expr):
        return f"({expr.p}.0 / {expr.q}.0)"

    def _print_Integer(self, expr):
        return f"{int(expr)}.0"

    def _print_Float(self, expr):
        return repr(float(expr))


# ------------------------------------------------------------------------------------------------ helpers
def _simplify(e):
    """A compact form of a trigonometric polynomial: sin^2 + cos^2 = 1 and cancellations found."""
    e = sp.expand(e)
    if e.has(sp.sin) or e.has(sp.cos):
        e = sp.expand(sp.trigsimp(e))
    return e


def _map_condition(c, f):
    """A Piecewise condition with f applied to the sides of its comparisons."""
    if isinstance(c, sp.core.relational.Relational):
        return c.func(f(c.lhs), f(c.rhs))
    if isinstance(c, (sp.And, sp.Or, sp.Not)):
        return c.func(*[_map_condition(a, f) for a in c.args])
    return c


class _Derived:
    """The parameter-only subexpressions of a model, computed once per instance into m->d[]."""

    def __init__(self, params: list):
        self.params = set(params)
        self.table: dict = {}          # expr -> symbol
        self.order: list = []          # (symbol, expr)

    def symbol(self, e, hint: str = ""):
        e = sp.sympify(e)
        if e.is_Number or e in self.params:
            return e
        if e not in self.table:
            s = sp.Symbol(f"d_{len(self.order)}" + (f"_{hint}" if hint else ""))
            self.table[e] = s
            self.order.append((s, e))
        return self.table[e]

    def hoist(self, e):
        """e with its maximal parameter-only subexpressions replaced by derived symbols."""
        if e.is_Atom:
            return e
        fs = e.free_symbols
        if not fs:
            return e
        if fs <= self.params:
            return self.symbol(e)
        if isinstance(e, sp.Piecewise):
            # a force law with branches (a slack tendon): each branch and each condition's sides hoisted
            return sp.Piecewise(*[(self.hoist(x), self._hoist_condition(c)) for x, c in e.args])
        if isinstance(e, (sp.Add, sp.Mul)):
            const = [a for a in e.args if a.free_symbols <= self.params]
            rest = [self.hoist(a) for a in e.args if not (a.free_symbols <= self.params)]
            if const:
                c = e.func(*const)
                c = c if c.is_Number else self.symbol(c)
                return e.func(c, *rest)
            return e.func(*rest)
        return e.func(*[self.hoist(a) for a in e.args])

    def _hoist_condition(self, c):
        return _map_condition(c, self.hoist)


def _c_double(x: float) -> str:
    if x == math.inf:
        return "INFINITY"
    if x == -math.inf:
        return "-INFINITY"
    return repr(float(x))


def _c_string(s: str) -> str:
    return '"' + s.replace("\\", "\\\\").replace('"', '\\"') + '"'


# ------------------------------------------------------------------------------------------------ the model
class ModelCode:
    """The generated C of one model class."""

    def __init__(self, cls):
        self.cls = cls
        self.kind = cls.kind
        self.prefix = "g_" + re.sub(r"\W", "_", cls.kind)
        self._sincos = "rk_sincos"          # the C function the blocks call for a sine and cosine pair
        self.params = list(cls.parameters()) if hasattr(cls, "parameters") else list(cls.fields())
        self.pnames = [p.name for p in self.params]
        self.psym = {n: sp.Symbol(n, real=True) for n in self.pnames}
        dofs = cls.__dataclass_fields__["dof_names"].default
        self.dofs = list(dofs)
        self.n = len(self.dofs)
        self.q = [sp.Symbol(f"q_{d}", real=True) for d in self.dofs]
        self.v = [sp.Symbol(f"v_{d}", real=True) for d in self.dofs]
        self.ag, self.ag_v = sp.symbols("ag ag_v", real=True)
        fields = cls.__dataclass_fields__
        self.phi_i = fields["phi_index"].default
        self.slide_i = fields["slide_index"].default if "slide_index" in fields else cls.slide_index
        self.lift_i = fields["lift_index"].default if "lift_index" in fields else cls.lift_index

        class _P:
            pass
        p = _P()
        for n, s in self.psym.items():
            setattr(p, n, s)
        self.mech = cls.mechanics(sp, p, tuple(self.q), tuple(self.v))
        self.nc = len(self.mech.contacts)
        if self.nc != 2:
            raise ValueError(f"{cls.__name__}: the engine's contact modes are those of a two-corner base "
                             f"(2 contacts), not {self.nc}")
        self.D = _Derived(list(self.psym.values()))
        self.names = {}
        for i, n in enumerate(self.pnames):
            self.names[self.psym[n]] = f"m->p[{i}]"
        self._derive()

    # ----------------------------------------------------------------------------------- mechanics
    def _derive(self):
        mech, q, v = self.mech, self.q, self.v
        g = self.psym["g"]
        T = sp.sympify(mech.kinetic)
        V = sp.sympify(mech.potential)
        Dis = sp.sympify(mech.dissipation)
        Sx, Sy = (sp.sympify(s) for s in mech.first_moment)
        self.T, self.V, self.Sy = T, V, Sy
        pvec = [sp.diff(T, vi) for vi in v]
        self.M = sp.Matrix(self.n, self.n, lambda i, j: _simplify(sp.diff(pvec[i], v[j])))
        ge = g + self.ag_v
        f = []
        for i, qi in enumerate(q):
            gyro = sum(sp.diff(pvec[i], qj) * vj for qj, vj in zip(q, v)) - sp.diff(T, qi)
            fi = (-gyro - sp.diff(V, qi) - self.ag * sp.diff(Sx, qi) - ge * sp.diff(Sy, qi)
                  - sp.diff(Dis, v[i]))
            f.append(sp.expand(fi))
        self.f = sp.Matrix(f)
        self.K = sp.Matrix(self.n, self.n, lambda i, j: sp.diff(V, q[i], q[j]))
        self.C = sp.Matrix(self.n, self.n, lambda i, j: sp.diff(Dis, v[i], v[j]))
        self.stiff = any(e != 0 for e in self.K) or any(e != 0 for e in self.C)
        # a model whose forces depend on where the base stands (a tendon anchored in the ground): the sticking
        # modes' kernels read the base's horizontal offset from its rest position, m->offset (0 for the others:
        # their modes leave it to the driver, which adds it to the SHIFTED_OUTPUTS)
        slide = q[self.slide_i]
        self.offset = None
        if any(slide in e.free_symbols for e in list(self.f) + list(self.M)):
            self.offset = sp.Symbol("base_offset", real=True)
            self.names[self.offset] = "m->offset"
        self.X = [sp.sympify(c[0]) for c in mech.contacts]
        self.Y = [sp.sympify(c[1]) for c in mech.contacts]
        self.rest = [sp.sympify(r) for r in mech.rest]
        rest_sub = dict(zip(q, self.rest))
        self.X_rest = [sp.simplify(x.subs(rest_sub)) for x in self.X]
        self.WN = sp.Matrix(self.n, self.nc, lambda i, c: sp.diff(self.Y[c], q[i]))
        self.WT = sp.Matrix(self.n, self.nc, lambda i, c: sp.diff(self.X[c], q[i]))
        self.aN = [sp.expand(sum(sp.diff(self.Y[c], qi, qj) * vi * vj for qi, vi in zip(q, v) for qj, vj in zip(q, v)))
                   for c in range(self.nc)]
        self.aT = [sp.expand(sum(sp.diff(self.X[c], qi, qj) * vi * vj for qi, vi in zip(q, v) for qj, vj in zip(q, v)))
                   for c in range(self.nc)]
        self.Sy_rest = sp.simplify(Sy.subs(rest_sub))
        self.energy = T + V + g * (Sy - self.Sy_rest)
        self.modes = {mode: self._mode(mode) for mode in STICKING}

    def _mode(self, mode):
        """Reduced coordinates, embedding, reduced dynamics and contact forces of a sticking mode."""
        q, v, n = self.q, self.v, self.n
        sub = {}
        off = 0 if self.offset is None else self.offset
        if mode == FULL:
            for i in (self.slide_i, self.lift_i, self.phi_i):
                sub[q[i]] = self.rest[i]
            sub[q[self.slide_i]] = self.rest[self.slide_i] + off
        elif mode in (LEFT, RIGHT):
            c = CLOSED[mode][0]
            unknown = [q[self.slide_i], q[self.lift_i]]
            eqs = [self.X[c] - self.X_rest[c] - off, self.Y[c]]
            sol = sp.solve(eqs, unknown, dict=True)
            if len(sol) != 1:
                raise ValueError(f"{self.cls.__name__}: the pivot's position does not fix the base's translations")
            sub = {k: sp.simplify(e) for k, e in sol[0].items()}
        idx = [i for i in range(n) if q[i] not in sub]
        r = [q[i] for i in idx]
        rd = [v[i] for i in idx]
        k = len(r)
        q_r = [sub.get(qi, qi) for qi in q]
        J = sp.Matrix(q_r).jacobian(r) if k else sp.zeros(n, 0)
        v_r = list(J * sp.Matrix(rd)) if k else [sp.Integer(0)] * n
        jd = list((J * sp.Matrix(rd)).jacobian(r) * sp.Matrix(rd)) if k else [sp.Integer(0)] * n
        jd = [_simplify(e) for e in jd]
        on_r = dict(zip(q, q_r))
        on_r.update(zip(v, v_r))
        Mq = self.M.subs(on_r)
        fq = self.f.subs(on_r)
        rdd = [sp.Symbol(f"rdd_{i}", real=True) for i in range(k)]
        Mr = (J.T * Mq * J).applyfunc(_simplify) if k else sp.zeros(0, 0)
        fr = (J.T * (fq - Mq * sp.Matrix(jd))).applyfunc(_simplify) if k else sp.zeros(0, 1)
        # the closed corners' forces: the rows of M q_dd - f along the base's translations (and rotation with
        # two closed corners) = W lambda, with unknowns lambda_N of each closed corner and the sum of lambda_T
        closed = CLOSED[mode]
        lam, totals = {}, None
        if closed:
            qdd = [sum(J[i, j] * rdd[j] for j in range(k)) + jd[i] for i in range(n)]
            res = Mq * sp.Matrix(qdd) - fq
            rows = [self.lift_i, self.slide_i, self.phi_i][:len(closed) + 1]
            A = sp.Matrix([[self.WN[i, c].subs(on_r) for c in closed] + [self.WT[i, closed[0]].subs(on_r)]
                           for i in rows])
            A = A.applyfunc(sp.simplify)
            x = A.LUsolve(sp.Matrix([res[i] for i in rows]))
            x = [sp.expand(e) for e in x]
            lam = {c: x[j] for j, c in enumerate(closed)}
            totals = (sum(x[:len(closed)]), x[len(closed)])
        gaps = [_simplify(self.Y[c].subs(on_r)) for c in range(self.nc)]
        phi = q_r[self.phi_i]
        outs = self._outputs(mode, q_r, v_r)
        return dict(idx=idx, r=r, rd=rd, k=k, q_r=q_r, v_r=v_r, J=J, jd=jd, Mr=Mr, fr=fr, rdd=rdd, lam=lam,
                    totals=totals, gaps=gaps, phi=phi, outs=outs)

    def _at_zero(self, e):
        """e at a zero base offset (the embedding: the driver adds the offset)."""
        return e if self.offset is None else sp.sympify(e).subs(self.offset, 0)

    def _outputs(self, mode, q_r, v_r):
        """The declared outputs on the embedding of a mode (None: the full-state generic slip); those that move
        with the base's offset (SHIFTED_OUTPUTS) at a zero offset: the driver adds it."""
        on_mode = dict(zip(self.q, q_r))
        on_mode.update(zip(self.v, v_r))
        on_zero = {k: self._at_zero(e) for k, e in on_mode.items()}
        out = []
        for p in self.cls.OUTPUTS:
            on = on_zero if p.name in self.cls.SHIFTED_OUTPUTS else on_mode
            e = self.mech.outputs[p.name]
            if isinstance(e, str) and e == "slip":
                if mode == FLIGHT:
                    out.append(None)
                else:
                    pivot = CLOSED[mode][0]
                    out.append(_simplify((self.X[pivot] - self.X_rest[pivot]).subs(on)))
            elif isinstance(e, str) and e == "energy":
                out.append(_simplify(self.energy.subs(on)) if mode != FLIGHT else self.energy)
            else:
                out.append(_simplify(sp.sympify(e).subs(on)))
        return out

    # ----------------------------------------------------------------------------------- emission
    def _block(self, targets: list, indent: str = "    ", keep: bool = False) -> str:
        """C statements assigning each (lhs, expr) after hoisting and common-subexpression elimination. With
        ``keep``, the sines and cosines computed by the previous blocks of the same scope are reused."""
        if not keep:
            self._scope = {}
        exprs = [self.D.hoist(self._canonical(sp.sympify(e))) for _, e in targets]
        exprs = [e.xreplace(self._scope) for e in exprs]
        self._n_blocks = getattr(self, "_n_blocks", 0) + 1
        repl, red = sp.cse(exprs, symbols=sp.numbered_symbols(f"t{self._n_blocks}_"), optimizations="basic")
        pr = _Printer(self._names_all())
        # a sine and a cosine of the same argument from one call of rk_sincos (memoised: the kernels evaluated at
        # one state ask them again), where the first of the two was computed; the other line goes
        trig: dict = {}
        for s, e in repl:
            if isinstance(e, (sp.sin, sp.cos)):
                trig.setdefault(e.args[0], {})[e.func] = s
        pairs = {a: d for a, d in trig.items() if len(d) == 2}
        lines, done = [], set()
        for s, e in repl:
            if isinstance(e, (sp.sin, sp.cos)) and e.args[0] in pairs:
                if e.args[0] not in done:
                    done.add(e.args[0])
                    sn, cs = (pr.doprint(pairs[e.args[0]][f]) for f in (sp.sin, sp.cos))
                    lines.append(f"{indent}double {sn}, {cs};")
                    lines.append(f"{indent}{self._sincos}(m, {pr.doprint(e.args[0])}, &{sn}, &{cs});")
                continue
            lines.append(f"{indent}const double {pr.doprint(s)} = {pr.doprint(e)};")
        for (lhs, _), e in zip(targets, red):
            lines.append(f"{indent}{lhs} = {pr.doprint(e)};")
        self._scope.update({e: s for s, e in repl if isinstance(e, (sp.sin, sp.cos))})
        return "\n".join(lines)

    def _canonical(self, e):
        """e as a polynomial in the state (coordinates, velocities, their sines and cosines, accelerations):
        one parameter-only coefficient per monomial (computed once per instance), grouped by the ground
        accelerations; non-polynomial parts are treated the same way argument by argument."""
        if e.is_Atom or not (e.free_symbols - self.D.params):
            return e
        if isinstance(e, sp.Piecewise):
            return sp.Piecewise(*[(self._canonical(x), self._canonical_condition(c)) for x, c in e.args])
        params = self.D.params
        gens = sorted({a for a in e.atoms(sp.Symbol) if a not in params}
                      | {f for f in e.atoms(sp.sin, sp.cos) if f.free_symbols - params}, key=sp.default_sort_key)
        try:
            poly = sp.Poly(e, *gens)
            if any(c.free_symbols - params for c in poly.coeffs()):
                raise sp.PolynomialError
        except (sp.PolynomialError, sp.GeneratorsNeeded, sp.CoercionFailed):
            return e.func(*[self._canonical(a) for a in e.args])
        groups = {}
        special = [g for g in (self.ag, self.ag_v) if g in gens]
        for monom, coeff in poly.terms():
            powers = dict(zip(gens, monom))
            key = tuple(powers.get(g, 0) for g in special)
            rest = sp.Mul(*[g ** k for g, k in powers.items() if g not in special and k])
            groups.setdefault(key, []).append(sp.factor_terms(coeff) * rest)
        out = []
        for key, terms in sorted(groups.items()):
            factor = sp.Mul(*[g ** k for g, k in zip(special, key) if k])
            out.append(factor * sp.Add(*terms) if factor != 1 else sp.Add(*terms))
        return sp.Add(*out)

    def _canonical_condition(self, c):
        return _map_condition(c, self._canonical)

    def _collect(self, e):
        """e grouped by the ground accelerations (fewer products than the expanded sum)."""
        if not (e.has(self.ag) or e.has(self.ag_v)) or e.is_Atom:
            return e
        if isinstance(e, sp.Add):
            e = sp.collect(e, [self.ag, self.ag_v])
            if not isinstance(e, sp.Add):
                return self._collect(e)
            return e.func(*[a if a.is_Atom else a.func(*[self._collect(b) for b in a.args]) for a in e.args])
        return e.func(*[self._collect(a) for a in e.args])

    def _names_all(self) -> dict:
        names = {}
        for i, (s, _) in enumerate(self.D.order):
            names[s] = f"m->d[{i}]"
        names[self.ag] = "ag"
        names[self.ag_v] = "ag_v"
        for i in range(self.n):
            names[self.q[i]] = f"q[{i}]"
            names[self.v[i]] = f"v[{i}]"
        names.update(self.names)
        return names

    def _y_names(self, md) -> dict:
        """Symbols of a mode's reduced coordinates read from y = [r, r_dot]."""
        k = md["k"]
        names = {}
        for j in range(k):
            names[md["r"][j]] = f"y[{j}]"
            names[md["rd"][j]] = f"y[{k + j}]"
            names[md["rdd"][j]] = f"rdd[{j}]"
        return names

    @staticmethod
    def _r_names(md) -> dict:
        """Symbols of a mode's reduced coordinates read from the arguments r, r_dot."""
        names = {md["r"][j]: f"r[{j}]" for j in range(md["k"])}
        names.update({md["rd"][j]: f"r_dot[{j}]" for j in range(md["k"])})
        return names

    def _with_names(self, extra: dict, fn):
        saved = self.names
        self.names = dict(saved)
        self.names.update(extra)
        try:
            return fn()
        finally:
            self.names = saved

    def _rdd_code(self, md) -> str:
        """Statements computing rdd[0..k-1] of a mode from y, ag, ag_v."""
        k = md["k"]
        if k == 0:
            return ""
        Mr, fr = md["Mr"], md["fr"]
        diagonal = all(Mr[i, j] == 0 for i in range(k) for j in range(k) if i != j)
        if k == 1 or diagonal:
            return self._block([(f"rdd[{i}]", fr[i] / Mr[i, i]) for i in range(k)])
        if k == 2:
            body = self._block([("Mr00", Mr[0, 0]), ("Mr01", Mr[0, 1]), ("Mr11", Mr[1, 1]), ("fr0", fr[0]),
                                ("fr1", fr[1])])
            return ("    double Mr00, Mr01, Mr11, fr0, fr1, det;\n" + body + "\n"
                    "    det = Mr00 * Mr11 - Mr01 * Mr01;\n"
                    "    rdd[0] = (Mr11 * fr0 - Mr01 * fr1) / det;\n"
                    "    rdd[1] = (Mr00 * fr1 - Mr01 * fr0) / det;")
        targets = [(f"Mr[{i * k + j}]", Mr[i, j]) for i in range(k) for j in range(k)]
        targets += [(f"fr[{i}]", fr[i]) for i in range(k)]
        return (f"    double Mr[{k * k}], fr[{k}];\n" + self._block(targets) + "\n"
                f"    if (rk_la_solve({k}, Mr, fr, rdd) != RK_OK) {{\n"
                f"        int i_;\n        for (i_ = 0; i_ < {k}; i_++)\n            rdd[i_] = NAN;\n    }}")

    def emit(self) -> str:
        P = self.prefix
        out = []
        w = out.append
        cls = self.cls
        mech = self.mech
        # ---- tables
        w(f"/* ======================================================================== {cls.__name__} ({self.kind}) */")
        w(self._decl_table(f"{P}_PARAMS", self.params))
        w(self._decl_table(f"{P}_INITIAL", list(cls.INITIAL)))
        w(self._decl_table(f"{P}_OUTPUTS", list(cls.OUTPUTS)))
        out_names = [p.name for p in cls.OUTPUTS]
        shifted = [out_names.index(s) for s in cls.SHIFTED_OUTPUTS]
        w(f"static const int {P}_SHIFTED[{max(1, len(shifted))}] = {{{', '.join(map(str, shifted)) or '0'}}};")
        # every function body is generated first (they fill the derived table), then init
        funcs = []
        funcs.append(self._emit_full())
        funcs.append(self._emit_modes())
        funcs.append(self._emit_outputs())
        funcs.append(self._emit_initial())
        if mech.classical_impact is not None:
            funcs.append(self._emit_classical())
        if mech.work_note is not None:
            funcs.append(self._emit_work_note())
        if mech.switches:
            funcs.append(self._emit_switches())
        init = self._emit_init()
        w(init)
        out.extend(funcs)
        w(self._emit_ops(len(shifted)))
        return "\n".join(out)

    def _decl_table(self, name, decls) -> str:
        rows = []
        for p in decls:
            unit = p.unit or ""
            if p.items:
                items = "{" + ", ".join(_c_string(it[0]) for it in p.items) + "}"
                rows.append((f"{name}_{p.name}_items", items, len(p.items)))
        lines = [f"static const char *const {n}[] = {items};" for n, items, _ in rows]
        lines.append(f"static const rk_param_decl {name}[{max(1, len(decls))}] = {{")
        for p in decls:
            unit = p.unit or ""
            if p.items:
                lines.append(f"    {{{_c_string(p.name)}, \"\", {float(p.default)!r}, 0.0, {len(p.items) - 1}.0, 0, 0, 0, "
                             f"1, {len(p.items)}, {name}_{p.name}_items}},")
                continue
            lo = -math.inf if p.lo is None else float(p.lo)
            hi = math.inf if p.hi is None else float(p.hi)
            lo_open = 1 if (p.lo_open or p.lo is None) else 0
            hi_open = 0 if p.inf_ok else (1 if (p.hi_open or p.hi is None) else 0)
            default = float(p.default) if isinstance(p.default, (int, float)) else 0.0
            lines.append(f"    {{{_c_string(p.name)}, {_c_string(unit)}, {_c_double(default)}, {_c_double(lo)}, "
                         f"{_c_double(hi)}, {lo_open}, {hi_open}, {int(p.inf_ok)}, 0, 0, NULL}},")
        if not decls:
            lines.append("    {\"\", \"\", 0.0, 0.0, 0.0, 0, 0, 0, 0, 0, NULL},")
        lines.append("};")
        return "\n".join(lines)

    def _emit_full(self) -> str:
        P, n, nc = self.prefix, self.n, self.nc
        s = []
        s.append(f"static void {P}_mass_matrix(const rk_model *m, const double *q, double *M)\n{{\n    (void)q;\n"
                 + self._block([(f"M[{i * n + j}]", self.M[i, j]) for i in range(n) for j in range(n)]) + "\n}\n")
        diagonal = all(self.M[i, j] == 0 for i in range(n) for j in range(n) if i != j)
        self.has_inverse = diagonal
        if diagonal:
            s.append(f"static void {P}_inverse_mass_matrix(const rk_model *m, const double *q, double *Minv)\n{{\n"
                     "    (void)q;\n"
                     + self._block([(f"Minv[{i * n + j}]", (1 / self.M[i, i]) if i == j else 0)
                                    for i in range(n) for j in range(n)]) + "\n}\n")
        s.append(f"static void {P}_forces(const rk_model *m, const double *q, const double *v, double ag, double ag_v, "
                 "double *f)\n{\n    (void)q; (void)v; (void)ag; (void)ag_v;\n"
                 + self._block([(f"f[{i}]", self.f[i]) for i in range(n)]) + "\n}\n")
        if self.stiff:
            s.append(f"static int {P}_stiff_jacobians(const rk_model *m, const double *q, const double *v, double *K, "
                     "double *C)\n{\n    (void)q; (void)v;\n"
                     + self._block([(f"K[{i * n + j}]", self.K[i, j]) for i in range(n) for j in range(n)]
                                   + [(f"C[{i * n + j}]", self.C[i, j]) for i in range(n) for j in range(n)])
                     + "\n    return 1;\n}\n")
        s.append(f"static void {P}_gaps(const rk_model *m, const double *q, double *g)\n{{\n"
                 + self._block([(f"g[{c}]", self.Y[c]) for c in range(nc)]) + "\n}\n")
        s.append(f"static void {P}_contact_jacobians(const rk_model *m, const double *q, double *W_N, double *W_T)\n{{\n"
                 "    (void)q;\n"
                 + self._block([(f"W_N[{i * nc + c}]", self.WN[i, c]) for i in range(n) for c in range(nc)]
                               + [(f"W_T[{i * nc + c}]", self.WT[i, c]) for i in range(n) for c in range(nc)])
                 + "\n}\n")
        s.append(f"static void {P}_contact_drift(const rk_model *m, const double *q, const double *v, double *a_N, "
                 "double *a_T)\n{\n    (void)q; (void)v;\n"
                 + self._block([(f"a_N[{c}]", self.aN[c]) for c in range(nc)]
                               + [(f"a_T[{c}]", self.aT[c]) for c in range(nc)]) + "\n}\n")
        s.append(f"static void {P}_contact_abscissae(const rk_model *m, const double *q, double *x)\n{{\n"
                 + self._block([(f"x[{c}]", self.X[c]) for c in range(nc)]) + "\n}\n")
        s.append(f"static void {P}_rest_position(const rk_model *m, double *q)\n{{\n    (void)m;\n"
                 + self._block([(f"q[{i}]", self.rest[i]) for i in range(n)]) + "\n}\n")
        s.append(f"static double {P}_energy(const rk_model *m, const double *q, const double *v)\n{{\n"
                 "    double e;\n" + self._block([("e", self.energy)]) + "\n    return e;\n}\n")
        return "\n".join(s)

    def _switch(self, cases: dict, default: str = "") -> str:
        lines = ["    switch (mode) {"]
        for mode, body in cases.items():
            lines.append(f"    case {MODE_NAME[mode]}: {{")
            lines.append("\n".join("    " + ln if ln else ln for ln in body.split("\n")))
            lines.append("        break;\n    }")
        lines.append("    default:\n" + (default or "        break;"))
        lines.append("    }")
        return "\n".join(lines)

    def _emit_modes(self) -> str:
        P, n, nc = self.prefix, self.n, self.nc
        s = []
        # mode_dofs
        cases = {}
        for mode, md in self.modes.items():
            cases[mode] = "\n".join(f"    idx[{j}] = {i};" for j, i in enumerate(md["idx"])) + f"\n    return {md['k']};"
        s.append(f"static int {P}_mode_dofs(const rk_model *m, int mode, int *idx)\n{{\n    (void)m; (void)idx;\n"
                 + self._switch(cases, "        return 0;") + "\n    return 0;\n}\n")
        # embed
        cases = {}
        for mode, md in self.modes.items():
            names = self._r_names(md)
            cases[mode] = self._with_names(names, lambda md=md: self._block(
                [(f"q[{i}]", self._at_zero(md["q_r"][i])) for i in range(n)]
                + [(f"v[{i}]", self._at_zero(md["v_r"][i])) for i in range(n)]))
        s.append(f"static void {P}_embed(const rk_model *m, int mode, const double *r, const double *r_dot, double *q, "
                 "double *v)\n{\n    (void)r; (void)r_dot;\n" + self._switch(cases) + "\n}\n")
        # mode_jacobian
        cases = {}
        for mode, md in self.modes.items():
            names = self._r_names(md)
            k = md["k"]
            cases[mode] = self._with_names(names, lambda md=md, k=k: self._block(
                [(f"J[{i * k + j}]", self._at_zero(md["J"][i, j])) for i in range(n) for j in range(k)]
                + [(f"jd[{i}]", self._at_zero(md["jd"][i])) for i in range(n)]))
        s.append(f"static void {P}_mode_jacobian(const rk_model *m, int mode, const double *r, const double *r_dot, "
                 "double *J, double *jd)\n{\n    (void)r; (void)r_dot; (void)J;\n" + self._switch(cases) + "\n}\n")
        # rhs
        cases = {}
        for mode, md in self.modes.items():
            k = md["k"]
            if k == 0:
                cases[mode] = ""
                continue
            body = self._with_names(self._y_names(md), lambda md=md: self._rdd_code(md))
            moves = "\n".join(f"    dy[{j}] = y[{k + j}];" for j in range(k))
            cases[mode] = f"    double rdd[{k}];\n" + body + "\n" + moves + "\n" + "\n".join(
                f"    dy[{k + j}] = rdd[{j}];" for j in range(k))
        s.append(f"static void {P}_mode_rhs(const rk_model *m, int mode, const double *y, double ag, double ag_v, "
                 "double *dy)\n{\n    (void)y; (void)ag; (void)ag_v; (void)dy;\n" + self._switch(cases) + "\n}\n")
        # mode_acc1: r_ddot of the one-dof modes alone, the same statements as mode_rhs's, from and to registers.
        # Only the Runge-Kutta stages call it, at points the memo cannot hold: rk_sincos_fresh skips the lookup
        # and keeps the values for the evaluations at the step's end that follow its last stage
        cases = {}
        self._sincos = "rk_sincos_fresh"
        for mode, md in self.modes.items():
            if md["k"] == 1:
                body = self._with_names(self._y_names(md), lambda md=md: self._rdd_code(md))
                cases[mode] = "    double rdd[1];\n" + body + "\n    return rdd[0];"
        self._sincos = "rk_sincos"
        self.has_acc1 = bool(cases)
        if cases:
            s.append(f"static double {P}_mode_acc1(const rk_model *m, int mode, double y0, double y1, double ag, "
                     "double ag_v)\n{\n    const double y[2] = {y0, y1};\n    (void)m; (void)y; (void)ag; (void)ag_v;\n"
                     + self._switch(cases) + "\n    return NAN;\n}\n")
        # monitor_one: the open gaps and the margin (no ag, no forces)
        cases = {}
        L = self.D.symbol(self.mech.length_scale, "L")
        for mode, md in self.modes.items():
            names = self._y_names(md)
            parts = []
            for c in range(nc):
                if c in CLOSED[mode]:
                    continue
                body = self._with_names(names, lambda md=md, c=c: self._block([("*gi", md["gaps"][c] / L)], "        "))
                parts.append(f"    if (i == {c}) {{\n{body}\n        return 1;\n    }}")
            body = self._with_names(names, lambda md=md: self._block([("*gi", HALF_PI - sp.Abs(md["phi"]))], "        "))
            parts.append(f"    if (i == {nc}) {{\n{body}\n        return 1;\n    }}")
            cases[mode] = "\n".join(parts) + "\n    return 0;"
        s.append(f"static int {P}_mode_monitor_one(const rk_model *m, int mode, const double *y, int i, double *gi)\n"
                 "{\n    (void)m; (void)y; (void)gi;\n" + self._switch(cases, "        return 0;") + "\n    return 0;\n}\n")
        # monitors (and totals): the closed corners' forces over the force scale, the open ones from monitor_one
        cases = {}
        Fs = self.D.symbol(self.mech.force_scale, "force_scale")
        for mode, md in self.modes.items():
            k = md["k"]
            names = self._y_names(md)
            lines = []
            for c in range(nc):
                if c not in CLOSED[mode]:
                    lines.append(f"    {P}_mode_monitor_one(m, mode, y, {c}, &g[{c}]);")
            lines.append(f"    {P}_mode_monitor_one(m, mode, y, {nc}, &g[{nc}]);")
            if CLOSED[mode]:
                rdd = f"    double rdd[{max(k, 1)}];\n    (void)rdd;\n" + self._with_names(names, lambda md=md: self._rdd_code(md))
                targets = [(f"g[{c}]", md["lam"][c] / Fs) for c in CLOSED[mode]]
                forces = self._with_names(names, lambda t=targets: self._block(t, keep=True))
                # the open gaps as monitor_one writes them, from the sines and cosines the acceleration computed
                # (a call would evaluate its own sine: the compiler cannot merge it with the sincos above)
                gaps = [self._with_names(names, lambda md=md, c=c: self._block([(f"g[{c}]", md["gaps"][c] / L)],
                                                                               keep=True))
                        for c in range(nc) if c not in CLOSED[mode]]
                tot = self._with_names(names, lambda md=md: self._block(
                    [("totals[0]", md["totals"][0]), ("totals[1]", md["totals"][1])], "        ", keep=True))
                lines = [rdd + "\n" + forces] + gaps + [f"    {P}_mode_monitor_one(m, mode, y, {nc}, &g[{nc}]);",
                                                       f"    if (totals != NULL) {{\n{tot}\n    }}"]
            cases[mode] = "\n".join(lines)
        s.append(f"static void {P}_mode_monitors(const rk_model *m, int mode, const double *y, double ag, double ag_v, "
                 "double *g, double *totals)\n{\n    (void)ag; (void)ag_v; (void)totals;\n" + self._switch(cases) + "\n}\n")
        # contact forces of a mode held closed, from the full state
        cases = {}
        for mode, md in self.modes.items():
            k = md["k"]
            lines = [f"    lam[{c}] = 0.0;" for c in range(nc)]
            if CLOSED[mode]:
                lines.append(f"    double y[{max(2 * k, 1)}], rdd[{max(k, 1)}];\n    (void)y; (void)rdd;")
                lines += [f"    y[{j}] = q[{i}];\n    y[{k + j}] = v[{i}];" for j, i in enumerate(md["idx"])]
                names = self._y_names(md)
                if self.offset is not None:
                    # the base's offset read off the full state: the pivot's abscissa (the base's, in full contact)
                    c = CLOSED[mode][0]
                    off = (self.q[self.slide_i] - self.rest[self.slide_i] if mode == FULL
                           else self.X[c] - self.X_rest[c])
                    lines.append("    double offset_q;\n" + self._block([("offset_q", off)]))
                    names[self.offset] = "offset_q"
                lines.append(self._with_names(names, lambda md=md: self._rdd_code(md)))
                lines.append(self._with_names(names, lambda md=md: self._block(
                    [(f"lam[{c}]", md["lam"][c]) for c in CLOSED[mode]], keep=True)))
            cases[mode] = "\n".join(lines)
        s.append(f"static void {P}_contact_forces(const rk_model *m, int mode, const double *q, const double *v, "
                 "double ag, double ag_v, double *lam)\n{\n    (void)q; (void)v; (void)ag; (void)ag_v;\n"
                 + self._switch(cases) + "\n}\n")
        return "\n".join(s)

    def _slip_code(self, indent="    ") -> str:
        """The generic slip of a full state: the lowest contact's abscissa from its rest position (first on
        ties)."""
        return self._block([("gs0", self.Y[0]), ("gs1", self.Y[1]), ("xs0", self.X[0] - self.X_rest[0]),
                            ("xs1", self.X[1] - self.X_rest[1])], indent)

    def _emit_outputs(self) -> str:
        P, n = self.prefix, self.n
        s = []
        targets, slip_at = [], None
        for i, p in enumerate(self.cls.OUTPUTS):
            e = self.mech.outputs[p.name]
            if isinstance(e, str) and e == "slip":
                slip_at = i
            elif isinstance(e, str) and e == "energy":
                targets.append((f"out[{i}]", self.energy))
            else:
                targets.append((f"out[{i}]", e))
        body = self._block(targets)
        if slip_at is not None:
            body += ("\n    {\n        double gs0, gs1, xs0, xs1;\n" + self._slip_code("        ")
                     + f"\n        out[{slip_at}] = gs1 < gs0 ? xs1 : xs0;\n    }}")
        s.append(f"static void {P}_outputs(const rk_model *m, const double *q, const double *v, double *out)\n{{\n"
                 + body + "\n}\n")
        cases = {}
        for mode, md in self.modes.items():
            if mode == FLIGHT:
                k = md["k"]
                cases[mode] = f"    {P}_outputs(m, y, y + {k}, out);"
                continue
            names = self._y_names(md)
            cases[mode] = self._with_names(names, lambda md=md: self._block(
                [(f"out[{i}]", e) for i, e in enumerate(md["outs"])]))
        s.append(f"static void {P}_mode_outputs(const rk_model *m, int mode, const double *y, double *out)\n{{\n"
                 "    (void)y;\n" + self._switch(cases) + "\n}\n")
        return "\n".join(s)

    def _emit_initial(self) -> str:
        """(mode, q, v) of the initial values: every `<dof>_0` / `<dof>_dot_0` sets that coordinate of the
        initial mode's reduced state (rk_mode_of_initial_state decides the mode from phi_0, phi_dot_0)."""
        P = self.prefix
        init = list(self.cls.INITIAL)
        names = [p.name for p in init]
        lines = [f"    double val[{max(1, len(init))}], r[RK_MAX_DOF], rd[RK_MAX_DOF];", "    int idx[RK_MAX_DOF], k, j;"]
        for i, p in enumerate(init):
            if p.name in self.mech.initial_bounds:
                lo, hi = self.mech.initial_bounds[p.name]
                dlo, dhi = self.D.symbol(lo, "lo"), self.D.symbol(hi, "hi")
                pr = _Printer(self._names_all())
                lines.append(f"    {{\n        rk_param_decl d_ = {P}_INITIAL[{i}];\n"
                             f"        d_.lo = {pr.doprint(dlo)};\n        d_.hi = {pr.doprint(dhi)};\n"
                             "        d_.lo_open = 0;\n        d_.hi_open = 0;\n"
                             f"        if (rk_param_check(&d_, initial[{i}], &val[{i}], err) != RK_OK)\n"
                             "            return RK_ERR_VALUE;\n    }")
            else:
                lines.append(f"    if (rk_param_check(&{P}_INITIAL[{i}], initial[{i}], &val[{i}], err) != RK_OK)\n"
                             "        return RK_ERR_VALUE;")
        phi = self.dofs[self.phi_i]
        lines.append(f"    *mode = rk_mode_of_initial_state(val[{names.index(phi + '_0')}], "
                     f"val[{names.index(phi + '_dot_0')}]);")
        lines.append(f"    k = {P}_mode_dofs(m, *mode, idx);")
        lines.append("    for (j = 0; j < k; j++) {\n        r[j] = 0.0;\n        rd[j] = 0.0;\n"
                     "        switch (idx[j]) {")
        for i, d in enumerate(self.dofs):
            a = names.index(d + "_0") if d + "_0" in names else None
            b = names.index(d + "_dot_0") if d + "_dot_0" in names else None
            if a is None and b is None:
                continue
            lines.append(f"        case {i}:" + (f" r[j] = val[{a}];" if a is not None else "")
                         + (f" rd[j] = val[{b}];" if b is not None else "") + " break;")
        lines.append("        default: break;\n        }\n    }")
        lines.append(f"    {P}_embed(m, *mode, r, rd, q, v);\n    return RK_OK;")
        return (f"static rk_status {P}_initial_state(const rk_model *m, const double *initial, int *mode, double *q, "
                "double *v, rk_error *err)\n{\n" + "\n".join(lines) + "\n}\n")

    def _emit_classical(self) -> str:
        P, n = self.prefix, self.n
        ci = self.mech.classical_impact
        rule = self.pnames.index(ci.param)
        cases = {}
        for mode in (LEFT, RIGHT):
            s_new = 1 if mode == LEFT else -1
            vp = ci.velocity(tuple(self.q), tuple(self.v), s_new)
            phi_dot = self.v[self.phi_i]
            cases[mode] = (f"    if (!({float(s_new)!r} * v_minus[{self.phi_i}] < 0.0))\n        return -1;\n"
                           + self._with_names({self.v[i]: f"v_minus[{i}]" for i in range(n)},
                                              lambda vp=vp: self._block([(f"v_plus[{i}]", e) for i, e in enumerate(vp)])))
            del phi_dot
        fin = " || ".join([f"!isfinite(q[{i}])" for i in range(n)] + [f"!isfinite(v_minus[{i}])" for i in range(n)])
        return (f"static int {P}_classical_impact_velocity(const rk_model *m, const double *q, const double *v_minus, "
                "int mode, double *v_plus)\n{\n"
                f"    int i_;\n    if ((int)m->p[{rule}] != {ci.code})\n        return 0;\n"
                f"    for (i_ = 0; i_ < {n}; i_++)\n        v_plus[i_] = NAN;\n"
                "    if (mode != RK_MODE_LEFT && mode != RK_MODE_RIGHT)\n        return -1;\n"
                f"    if ({fin})\n        return -1;\n"
                + self._switch(cases) + "\n    return 1;\n}\n")

    def _template(self, text: str):
        """A message template's printf format and its argument expressions (C)."""
        args = []

        def field(mo):
            name, fmt = mo.group(1), mo.group(2) or "g"
            sym = self.psym[name] if name in self.psym else self.D.symbol(self.mech.derived[name], name)
            args.append(_Printer(self._names_all()).doprint(sym))
            return "%" + fmt
        fmt = re.sub(r"\{(\w+)(?::([^}]+))?\}", field, text.replace("%", "%%"))
        return fmt, args

    def _emit_work_note(self) -> str:
        fmt, args = self._template(self.mech.work_note)
        return (f"static void {self.prefix}_work_note(const rk_model *m, char *buf, size_t n)\n{{\n    (void)m;\n"
                f"    snprintf(buf, n, {_c_string(fmt)}{''.join(', ' + a for a in args)});\n}}\n")

    def _emit_switches(self) -> str:
        targets = [(f"s[{i}]", sw.value / self.D.symbol(sw.scale, "switch_scale"))
                   for i, sw in enumerate(self.mech.switches)]
        return (f"static void {self.prefix}_switches(const rk_model *m, const double *q, const double *v, double *s)\n"
                "{\n    (void)q; (void)v;\n" + self._block(targets) + "\n}\n")

    def _emit_init(self) -> str:
        P, mech = self.prefix, self.mech
        n = self.n
        pr = lambda: _Printer(self._names_all())  # noqa: E731
        # the scales and the checks reference derived symbols too: register them before printing the table
        scales = {
            "length_scale": self.D.symbol(mech.length_scale, "L"),
            "time_scale": self.D.symbol(mech.time_scale, "T"),
            "force_scale": self.D.symbol(mech.force_scale, "force_scale"),
        }
        step = None if mech.step_limit is None else self.D.symbol(mech.step_limit, "step")
        self.named = [(name, self.D.symbol(e, name)) for name, e in mech.derived.items()]
        checks = []
        for chk in mech.checks:
            cond = self.D.symbol(sp.Piecewise((1, chk.fails), (0, True)), "check")
            checks.append((cond, *self._template(chk.message)))
        if len(self.D.order) > MAX_DERIVED:
            raise ValueError(f"{self.cls.__name__}: {len(self.D.order)} derived constants, more than "
                             f"RK_MAX_DERIVED = {MAX_DERIVED}")
        lines = [f"static rk_status {P}_init(rk_model *m, const double *params, rk_error *err)\n{{",
                 "    int i;",
                 f"    for (i = 0; i < {len(self.params)}; i++) {{",
                 f"        if (rk_param_check(&{P}_PARAMS[i], params[i], &m->p[i], err) != RK_OK)",
                 "            return RK_ERR_VALUE;", "    }"]
        p = pr()
        for i, (s, e) in enumerate(self.D.order):
            lines.append(f"    m->d[{i}] = {p.doprint(e)};")
        for cond, fmt, args in checks:
            lines.append(f"    if ({p.doprint(cond)} != 0.0)\n        return rk_fail(err, RK_ERR_VALUE, "
                         f"{_c_string(fmt)}{''.join(', ' + a for a in args)});")
        law = self.pnames.index("impact_law")
        lines += [f"    m->e_N = m->p[{self.pnames.index('e_N')}];",
                  f"    m->impact_law = (int)m->p[{law}];",
                  "    m->e_T = m->impact_law == 1 ? m->e_N : 0.0;",
                  f"    m->mu = m->p[{self.pnames.index('mu')}];",
                  f"    m->g = m->p[{self.pnames.index('g')}];",
                  f"    m->length_scale = {p.doprint(scales['length_scale'])};",
                  f"    m->time_scale = {p.doprint(scales['time_scale'])};",
                  f"    m->force_scale = {p.doprint(scales['force_scale'])};",
                  f"    m->step_limit = {'INFINITY' if step is None else p.doprint(step)};"]
        for i in range(n):
            lines.append(f"    m->dof_scales[{i}] = {'1.0' if i == self.phi_i else 'm->length_scale'};")
        lines.append("    return RK_OK;\n}\n")
        return "\n".join(lines)

    def _emit_named(self) -> str:
        """The declared derived quantities: names and places in m->d (a parameter itself: -1 - its index)."""
        P = self.prefix
        order = {s: i for i, (s, _) in enumerate(self.D.order)}
        params = {self.psym[n]: i for i, n in enumerate(self.pnames)}
        idx = [order[s] if s in order else -1 - params[s] for _, s in self.named]
        return (f"static const char *const {P}_NAMED[{max(1, len(idx))}] = "
                f"{{{', '.join(_c_string(n) for n, _ in self.named) or 'NULL'}}};\n"
                f"static const int {P}_NAMED_INDEX[{max(1, len(idx))}] = {{{', '.join(map(str, idx)) or '0'}}};\n")

    def _emit_ops(self, n_shifted) -> str:
        P, cls = self.prefix, self.cls
        mech = self.mech
        opt = lambda cond, name: f"{P}_{name}" if cond else "NULL"  # noqa: E731
        return self._emit_named() + (f"const rk_model_ops {P}_ops = {{\n"
                f"    {_c_string(self.kind)}, {_c_string(cls.__name__)},\n"
                f"    {self.n}, {self.nc}, 10,\n"
                f"    {self.phi_i}, {self.slide_i}, {self.lift_i},\n"
                f"    {len(self.params)}, {P}_PARAMS,\n"
                f"    {len(cls.INITIAL)}, {P}_INITIAL,\n"
                f"    {len(cls.OUTPUTS)}, {P}_OUTPUTS,\n"
                f"    {n_shifted}, {P}_SHIFTED,\n"
                f"    {P}_init,\n"
                "    rk_two_corner_mode_of, rk_two_corner_closed_of, rk_two_corner_stick_of,\n"
                f"    {P}_mass_matrix, {opt(self.has_inverse, 'inverse_mass_matrix')}, {P}_forces, "
                f"{opt(self.stiff, 'stiff_jacobians')},\n"
                f"    {P}_gaps, {P}_contact_jacobians, {P}_contact_drift, {P}_contact_abscissae,\n"
                f"    {P}_mode_dofs, {P}_embed, {P}_mode_jacobian, {P}_mode_rhs, {P}_mode_monitors,\n"
                f"    {P}_mode_outputs, {P}_contact_forces,\n"
                f"    {P}_rest_position, {P}_energy, {P}_outputs, {P}_initial_state,\n"
                f"    {opt(mech.classical_impact is not None, 'classical_impact_velocity')}, "
                f"{opt(mech.work_note is not None, 'work_note')},\n"
                f"    {P}_mode_monitor_one,\n"
                f"    {len(self.named)}, {P}_NAMED, {P}_NAMED_INDEX,\n"
                f"    {len(mech.switches)}, {opt(bool(mech.switches), 'switches')},\n"
                f"    {opt(self.has_acc1, 'mode_acc1')}\n}};\n")


# ------------------------------------------------------------------------------------------------ the file
def declared_models() -> list:
    """The registered model classes that declare their mechanics."""
    root = os.path.dirname(os.path.dirname(HERE))
    if root not in sys.path:
        sys.path.insert(0, root)
    models = importlib.import_module("rocking_model.models")
    return [cls for cls in models.MODELS.values() if hasattr(cls, "mechanics")]


def _source_file(cls) -> str:
    """The file a model class is declared in ("" when it has none: declared interactively, or its module gone)."""
    try:
        return inspect.getsourcefile(cls) or ""
    except (TypeError, OSError):
        return ""


def _inputs_hash(classes) -> str:
    h = hashlib.sha256()
    for path in sorted({_source_file(c) for c in classes} | {os.path.abspath(__file__)}):
        try:
            with open(path, "rb") as fh:
                h.update(fh.read())
        except OSError:               # a class declared interactively: its generated text is hashed by its user
            h.update(path.encode())
    h.update(sp.__version__.encode())
    return h.hexdigest()[:16]


def generate(classes=None) -> str:
    classes = declared_models() if classes is None else classes
    parts = [f"/* rk_models_gen.c -- GENERATED by rocking_model/engine/gen_models.py from the model declarations\n"
             f" * ({', '.join((_source_file(c) or c.__name__).split(os.sep)[-1] for c in classes)}); do not edit.\n"
             f" * inputs {_inputs_hash(classes)} */",
             "#include \"rk_fp.h\" /* first: no contraction into multiply-adds (rk_fp.h) */\n"
             "#include \"rk_model.h\"\n\n#include <math.h>\n#include <stdio.h>\n#include <string.h>\n"]
    names = []
    for cls in classes:
        code = ModelCode(cls)
        parts.append(code.emit())
        names.append(code.prefix + "_ops")
    parts.append("const rk_model_ops *const rk_generated_models[] = {\n"
                 + "".join(f"    &{n},\n" for n in names) + "    NULL\n};\n")
    return "\n".join(parts)


def main(out: str = OUT) -> bool:
    """Write the generated kernels if their inputs changed; returns whether the file was written."""
    classes = declared_models()
    stamp = f" * inputs {_inputs_hash(classes)} */"
    if os.path.exists(out):
        with open(out, encoding="utf-8") as fh:
            head = fh.read(600)
        if stamp in head:
            return False
    text = generate(classes)
    tmp = out + ".tmp"
    with open(tmp, "w", encoding="utf-8") as fh:
        fh.write(text)
    os.replace(tmp, out)
    return True


if __name__ == "__main__":
    wrote = main(sys.argv[1] if len(sys.argv) > 1 else OUT)
    print(f"gen_models: {'wrote' if wrote else 'up to date:'} {sys.argv[1] if len(sys.argv) > 1 else OUT}")
