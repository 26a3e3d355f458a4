"""Generate src/rk_tableaux.h, the Runge-Kutta tableaux of the C engine, from rocking_model/engine/tableaux.py.

The coefficients live in one place, tableaux.py (plain data), which this script reads with `ast` (no import: the
build environment has no numpy) and writes as C data, each combination sum_i c_i k_i as its nonzero terms in
index order (the order the C sums them in). Which lists form the error estimates and the dense-output rows is
read from each pair's ``error_rows`` and ``dense_rows``. The error norm and the interpolant are code, not data:
rk_rk.c implements each tableau's form (``style``).

Also records whether the Python that builds the extension sums floats with Neumaier's compensation
(``sum()`` since CPython 3.12): the C initial step size follows the interpreter it is built for (the results
recorded so far were computed that way).

Run by setup.py at every build; rewrites the header only when its content changes (no needless rebuild).
Usage: python rocking_model/engine/gen_rk.py (no arguments: setup.py runs it as __main__ with its own argv, so
the command line is ignored; `generate(path)` writes elsewhere)
"""
from __future__ import annotations

import ast
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
SOURCE = os.path.join(HERE, "tableaux.py")
OUTPUT = os.path.join(HERE, "src", "rk_tableaux.h")

#: the tableaux: (class name in tableaux.py, C style code); the style selects the error norm and interpolant
#: forms of rk_rk.c
TABLEAUX = [("DOP853", "RK_STYLE_DOP853"), ("DOPRI5", "RK_STYLE_DOPRI5")]
#: limits of rk_rk.h (RK_MAX_STAGES, RK_MAX_DENSE); checked here and in the generated header
MAX_STAGES = 16
MAX_DENSE = 8
MAX_ERRORS = 2


def _eval(node, env):
    """Value of a constant expression of the tableau sources: numbers, strings, lists, tuples, names bound earlier,
    unary minus and + (numbers, list concatenation)."""
    if isinstance(node, ast.Constant) and isinstance(node.value, (int, float, str)):
        return node.value
    if isinstance(node, ast.List):
        return [_eval(e, env) for e in node.elts]
    if isinstance(node, ast.Tuple):
        return tuple(_eval(e, env) for e in node.elts)
    if isinstance(node, ast.Name):
        if node.id not in env:
            raise ValueError(f"gen_rk: name {node.id!r} is not a constant of the tableau source")
        return env[node.id]
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
        v = _eval(node.operand, env)
        return -v if isinstance(node.op, ast.USub) else +v
    if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Add):
        return _eval(node.left, env) + _eval(node.right, env)
    raise ValueError(f"gen_rk: unsupported expression at line {getattr(node, 'lineno', '?')}: {ast.dump(node)}")


def _assign(stmt, env, into):
    """Bind the targets of a simple assignment (names or a tuple of names) in ``into``."""
    targets = stmt.targets if isinstance(stmt, ast.Assign) else [stmt.target]
    value = _eval(stmt.value, env)
    for target in targets:
        if isinstance(target, ast.Name):
            into[target.id] = value
        elif isinstance(target, ast.Tuple) and all(isinstance(e, ast.Name) for e in target.elts):
            if len(target.elts) != len(value):
                raise ValueError("gen_rk: tuple assignment of unequal lengths")
            for e, v in zip(target.elts, value):
                into[e.id] = v


def read_tableau(class_name, path=SOURCE):
    """The tableau of ``class_name`` in tableaux.py: a dict of name, order, error_order, n_stages, A, B, C,
    errors (list of lists), dense (list of rows)."""
    with open(path, encoding="utf-8") as fh:
        tree = ast.parse(fh.read(), filename=path)
    env: dict = {}
    cls = None
    for stmt in tree.body:
        if isinstance(stmt, (ast.Assign, ast.AnnAssign)) and stmt.value is not None:
            try:
                _assign(stmt, env, env)
            except ValueError:
                pass                    # not a constant (e.g. an object): not part of the tableau
        elif isinstance(stmt, ast.ClassDef) and stmt.name == class_name:
            cls = stmt
    if cls is None:
        raise ValueError(f"gen_rk: no class {class_name} in {path}")
    attrs: dict = {}
    for stmt in cls.body:
        if isinstance(stmt, (ast.Assign, ast.AnnAssign)) and stmt.value is not None:
            _assign(stmt, {**env, **attrs}, attrs)
    tab = {k: attrs[k] for k in ("name", "order", "error_order", "n_stages", "A", "B", "C")}
    tab["error_names"] = list(attrs["error_rows"])
    tab["dense_name"] = attrs["dense_rows"]
    tab["errors"] = [attrs[n] for n in tab["error_names"]]
    tab["dense"] = attrs[tab["dense_name"]]
    tab["source"] = os.path.relpath(path, os.path.join(HERE, os.pardir, os.pardir)).replace(os.sep, "/")
    return tab


def nonzero(coefs):
    """(indices, values) of the terms of a combination: the nonzero coefficients in index order."""
    idx = [i for i, c in enumerate(coefs) if float(c) != 0.0]
    return idx, [float(coefs[i]) for i in idx]


def _c_double(x: float) -> str:
    """An exact C99 literal (hexadecimal) of x, with its repr as a comment."""
    return f"{float(x).hex()} /* {float(x)!r} */"


def _c_lincomb(coefs, indent) -> str:
    idx, val = nonzero(coefs)
    if len(idx) > MAX_STAGES:
        raise ValueError("gen_rk: a combination has more terms than RK_MAX_STAGES")
    pad = " " * indent
    idx_s = ", ".join(str(i) for i in idx) or "0"
    val_s = (",\n" + pad + "   ").join(_c_double(v) for v in val) or "0.0"
    return f"{{{len(idx)}, {{{idx_s}}},\n{pad}  {{{val_s}}}}}"


def check(tab):
    ns, n_all = tab["n_stages"], len(tab["A"])
    if not (2 <= ns <= n_all <= MAX_STAGES) or len(tab["C"]) < n_all:
        raise ValueError(f"gen_rk: {tab['name']}: stage counts out of the limits ({ns}, {n_all}, {len(tab['C'])})")
    if len(tab["B"]) > ns - 1 or not 1 <= len(tab["errors"]) <= MAX_ERRORS or len(tab["dense"]) > MAX_DENSE:
        raise ValueError(f"gen_rk: {tab['name']}: B, error or dense rows out of the limits")
    for s, row in enumerate(tab["A"]):
        if len(row) > max(s, 0) and any(float(c) != 0.0 for c in row[s:]):
            raise ValueError(f"gen_rk: {tab['name']}: A[{s}] is not strictly lower triangular")
    for row in tab["errors"]:
        if len(row) > ns:
            raise ValueError(f"gen_rk: {tab['name']}: an error row uses more than the {ns} stages of a step")
    for row in tab["dense"]:
        if len(row) > n_all:
            raise ValueError(f"gen_rk: {tab['name']}: a dense row uses more than the {n_all} stages")


def render(tableaux, compensated_sum: bool) -> str:
    out = ["/* rk_tableaux.h -- GENERATED by rocking_model/engine/gen_rk.py at build time: do not edit, do not commit.",
           " *",
           " * The Runge-Kutta tableaux, read from " +
           ", ".join(sorted({t["source"] for t, _ in tableaux})) + ",",
           " * as C data: each combination sum_i c_i k_i lists its nonzero terms in index order (the C adds them in",
           " * that order). Included by rk_rk.c",
           " * only. Literals are hexadecimal (exact); the comments give the Python repr. */",
           "#ifndef RK_TABLEAUX_H", "#define RK_TABLEAUX_H", "",
           '#include "rk_rk.h"', "",
           "/* 1: the building Python's sum() of floats is Neumaier-compensated (CPython >= 3.12), followed by",
           " * the initial step size; 0: plain left-to-right addition (a -D on the command line overrides it,",
           " * for the test of both forms) */",
           "#ifndef RK_PY_SUM_COMPENSATED",
           f"#define RK_PY_SUM_COMPENSATED {1 if compensated_sum else 0}", "#endif", "",
           "/* the error-norm and interpolant forms of rk_rk.c */",
           "#define RK_STYLE_DOP853 0", "#define RK_STYLE_DOPRI5 1", "",
           "/* limits this file was generated for (rk_rk.h must allow them) */",
           f"typedef char rk_tableaux_stages_fit[(RK_MAX_STAGES >= {MAX_STAGES}) ? 1 : -1];",
           f"typedef char rk_tableaux_dense_fit[(RK_MAX_DENSE >= {MAX_DENSE}) ? 1 : -1];", "",
           "/** sum_i c[i] k_{idx[i]}: the nonzero terms of a combination, in index order */",
           "typedef struct rk_lincomb {", "    int n;", f"    int idx[{MAX_STAGES}];", f"    double c[{MAX_STAGES}];",
           "} rk_lincomb;", "",
           "struct rk_tableau {",
           "    const char *name;",
           "    int style;          /**< RK_STYLE_*: error norm and interpolant form */",
           "    int order;          /**< order of the propagated solution */",
           "    int error_order;    /**< order of the error estimate */",
           "    int n_stages;       /**< stages of a step, the last one f(t_new, y_new) (FSAL) */",
           "    int n_all;          /**< stages including the extra dense-output stages (len(A)) */",
           f"    double C[{MAX_STAGES}];",
           f"    rk_lincomb A[{MAX_STAGES}];  /**< A[s][:s] */",
           "    rk_lincomb B;",
           "    int n_errors;       /**< error estimates per component (er0, er1 of error_sources) */",
           f"    rk_lincomb E[{MAX_ERRORS}];",
           "    int n_dense;        /**< dense-output coefficient rows (dense_sources) */",
           f"    rk_lincomb D[{MAX_DENSE}];",
           "};", ""]
    out += ["/* the data: in rk_rk.c only (which defines RK_TABLEAUX_DEFINE_DATA) */", "#ifdef RK_TABLEAUX_DEFINE_DATA", ""]
    for tab, style in tableaux:
        n_all = len(tab["A"])
        C = list(tab["C"])[:MAX_STAGES] + [0.0] * (MAX_STAGES - min(len(tab["C"]), MAX_STAGES))
        out.append(f"/* {tab['name']}: {tab['source']}, errors from {', '.join(tab['error_names'])}, "
                   f"dense rows from {tab['dense_name']} */")
        out.append(f"static const struct rk_tableau RK_TABLEAU_{tab['name']} = {{")
        out.append(f"    \"{tab['name']}\", {style}, {int(tab['order'])}, {int(tab['error_order'])}, "
                   f"{int(tab['n_stages'])}, {n_all},")
        out.append("    {" + (",\n     ").join(_c_double(c) for c in C) + "},")
        rows = [_c_lincomb(list(tab["A"][s])[:s], 6) for s in range(n_all)]
        rows += ["{0, {0}, {0.0}}"] * (MAX_STAGES - n_all)
        out.append("    {" + (",\n     ").join(rows) + "},")
        out.append("    " + _c_lincomb(tab["B"], 4) + ",")
        errs = [_c_lincomb(e, 6) for e in tab["errors"]] + ["{0, {0}, {0.0}}"] * (MAX_ERRORS - len(tab["errors"]))
        out.append(f"    {len(tab['errors'])},")
        out.append("    {" + (",\n     ").join(errs) + "},")
        dense = [_c_lincomb(d, 6) for d in tab["dense"]] + ["{0, {0}, {0.0}}"] * (MAX_DENSE - len(tab["dense"]))
        out.append(f"    {len(tab['dense'])},")
        out.append("    {" + (",\n     ").join(dense) + "}")
        out.append("};")
        out.append("")
    out.append("#endif /* RK_TABLEAUX_DEFINE_DATA */")
    out.append("")
    out.append("#endif /* RK_TABLEAUX_H */")
    return "\n".join(out) + "\n"


def generate(path: str = OUTPUT) -> bool:
    """Write the header if its content changed; returns whether it was written."""
    tableaux = []
    for cls, style in TABLEAUX:
        tab = read_tableau(cls)
        check(tab)
        tableaux.append((tab, style))
    text = render(tableaux, compensated_sum=sys.version_info >= (3, 12))
    try:
        with open(path, encoding="utf-8") as fh:
            if fh.read() == text:
                return False
    except FileNotFoundError:
        pass
    tmp = path + ".tmp"
    with open(tmp, "w", encoding="utf-8", newline="\n") as fh:
        fh.write(text)
    os.replace(tmp, path)
    return True


if __name__ == "__main__":
    generate()
