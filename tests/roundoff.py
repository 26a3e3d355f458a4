"""Round-off robustness of the suite's long and violent scenes.

A long rocking history is chaotic: round-off (another CPU's BLAS kernel, libm variant or SIMD path) moves
it, and a test whose verdict round-off can flip fails on some machine sooner or later. The scenes of the
round-off-sensitive tests are therefore written as *named scenes* (functions of a `Perturbation`) whose
coarse outcome, the *verdict*, is far from any decision boundary, and every one of them is run three ways:

1. as the test runs it (nominal);
2. in-process with a 1-ulp perturbation of its initial state and of its input (``np.nextafter`` on phi_0
   and on every record sample or pulse parameter, each towards a random side, fixed seed);
3. in a subprocess whose arithmetic kernels differ from this machine's defaults (`kernel_env`: the libm
   variant glibc selects, OpenBLAS' core type, numpy's dispatched SIMD targets).

The verdicts (booleans: finite, no penetration beyond the documented tolerance over the whole run, each
pivot on its own side, overturned or not, exactly at rest at the end or not, energy below the tipping
energy, impact log bounded, ...) must be identical in all three; the figures (max |phi| / alpha, impacts,
...) are reported and checked against the documented margins.

Command line (what the subprocess runs; also handy to measure spreads):

    python tests/roundoff.py [--perturb SEED] MODULE:SCENE ...   # one JSON line per scene
    python tests/roundoff.py --fingerprint                      # hashes of the arithmetic kernels
"""
from __future__ import annotations

import dataclasses
import hashlib
import importlib
import json
import math
import os
import subprocess
import sys
import time
from pathlib import Path
from typing import Callable

import numpy as np

HERE = Path(__file__).resolve().parent
if str(HERE) not in sys.path:
    sys.path.insert(0, str(HERE))

#: scene registry: "module:name" -> function(Perturbation) -> (Trace, checks dict)
SCENES: dict[str, Callable] = {}
#: seed of the in-process 1-ulp perturbation the suite runs (others were measured, see the tests' docstrings)
ULP_SEED = 1
#: [s] a subprocess re-run of the scenes of one test module must finish within this (they take ~20 s)
SUBPROCESS_TIMEOUT = 300.0


@dataclasses.dataclass(frozen=True)
class Perturbation:
    """1-ulp perturbation of a scene's initial state and input: each number goes to its neighbouring float
    (``np.nextafter``) towards +inf or -inf, the side drawn per number from ``seed``. ``seed=None`` is the
    identity (the nominal run)."""

    seed: int | None = None

    def array(self, a, stream: int = 0) -> np.ndarray:
        """``a`` (e.g. record samples [m/s2]) with every entry moved by one ulp (stream: an independent draw
        for each quantity of a scene)."""
        a = np.asarray(a, dtype=float)
        if self.seed is None:
            return a.copy()
        rng = np.random.default_rng([self.seed, stream])
        return np.nextafter(a, np.where(rng.uniform(size=a.shape) < 0.5, -np.inf, np.inf))

    def scalar(self, x: float, stream: int = 0) -> float:
        """``x`` (e.g. phi_0 [rad], a pulse amplitude [m/s2]) moved by one ulp; 0 becomes +-5e-324."""
        return float(self.array(np.array([float(x)]), stream)[0])

    def __str__(self) -> str:
        return "nominal" if self.seed is None else f"1-ulp seed {self.seed}"


def scene(name: str):
    """Register a scene function under ``<module>:<name>`` (the module being the caller's)."""
    module = sys._getframe(1).f_globals["__name__"]

    def deco(fun):
        key = f"{module}:{name}"
        SCENES[key] = fun
        fun.scene_key = key
        return fun
    return deco


# --------------------------------------------------------------------------------------------- verdicts
def summarize(tr, checks: dict | None = None) -> dict:
    """``{"verdict": {...}, "figures": {...}}`` of a finished `Trace` (tests/hard_cases.py).

    checks (all optional): ``rest_after`` [s]: from this time on the body must be exactly at rest (full
    contact, phi = phi_dot = 0); ``log_size``: the bounded impact log's length; ``pen`` [m]: penetration
    tolerance (default `pen_tol`); ``tipping_energy`` (default True): False drops the verdict
    energy_below_tipping (its figure stays), which certifies nothing under a vertical ground motion (the
    energy keeps g, the ground works on the body); ``verdict`` / ``figures``: the scene's own booleans /
    numbers (e.g. flight seen), added as they are."""
    from hard_cases import sanity_report
    from rocking_model.modes import Mode
    from rocking_model import RigidBlock

    checks = checks or {}
    model = tr.model
    rep = sanity_report(tr, overturn_ok=True, pen=checks.get("pen"))
    T, phi, modes = tr.T, tr.phi, tr.modes
    over = np.asarray(tr.overturned, dtype=bool)
    k_ov = int(np.argmax(over)) if over.any() else len(T)
    verdict = {k: bool(rep[k]) for k in ("finite", "no_penetration", "right_side", "bounded_rotation")}
    verdict["overturned"] = bool(over.any())
    if over.any():
        q = np.array(tr.q)
        verdict["frozen_after_overturning"] = bool(np.all(q[k_ov:] == q[k_ov]))
    if checks.get("rest_after") is not None:
        w = T >= checks["rest_after"]
        verdict["at_rest_at_end"] = bool(np.all(modes[w] == Mode.FULL) and np.all(phi[w] == 0.0)
                                         and np.all(tr.phi_dot[w] == 0.0))
    if checks.get("log_size") is not None:
        log = tr.sim.impact_times
        verdict["impact_log_bounded"] = bool(len(log) <= checks["log_size"] and log == sorted(log)
                                             and (not log or log[-1] <= T[-1]))
    rocking = modes != Mode.FULL
    figures = {
        "max_phi_over_alpha": float(np.max(np.abs(phi[:k_ov]))) / model.alpha if k_ov else 0.0,
        "impacts": int(tr.impacts[-1]),
        "episodes": int(np.count_nonzero(rocking[1:] & ~rocking[:-1])),
        "t_overturn": float(T[k_ov]) if over.any() else None,
        "min_gap_checked": rep["min_gap"],
        "pen_tol": rep["tol"],
        "wall_s": float(getattr(tr, "wall", 0.0)),
    }
    if isinstance(model, RigidBlock) and not over.any():
        # tipping energy: potential energy with the centroid above the pivot; a block below it that is not
        # driven cannot overturn (e_N = 0: energy does not grow without input)
        e_tip = model.m * model.g * model.R * (1.0 - math.cos(model.alpha))
        figures["max_E_over_E_tip"] = float(np.max(tr.energy)) / e_tip
        if checks.get("tipping_energy", True):
            verdict["energy_below_tipping"] = figures["max_E_over_E_tip"] < 1.0
    verdict.update({k: bool(x) for k, x in checks.get("verdict", {}).items()})
    figures.update(checks.get("figures", {}))
    return {"verdict": verdict, "figures": figures, "messages": rep["messages"]}


def run_scene(key: str, pert: Perturbation = Perturbation()):
    """(trace, summary) of a registered scene ``module:name``."""
    module, _, _ = key.partition(":")
    if key not in SCENES:
        importlib.import_module(module)
    fun = SCENES[key]
    t0 = time.perf_counter()
    tr, checks = fun(pert)
    tr.wall = time.perf_counter() - t0
    return tr, summarize(tr, checks)


def describe_mismatch(a: dict, b: dict) -> str:
    keys = sorted(set(a) | set(b))
    return ", ".join(f"{k}: {a.get(k)} vs {b.get(k)}" for k in keys if a.get(k) != b.get(k))


# --------------------------------------------------------------------------------------------- kernels
def fingerprint() -> dict:
    """Hashes of results of the arithmetic kernels a scene goes through: libm (``math.sin`` & co, what the
    event-driven right-hand sides call), numpy's ufuncs, BLAS/LAPACK (``@``, ``inv``) and the synthetic
    record (scipy's ``lsim``). Two environments with equal hashes compute the same numbers."""
    from rocking_model.records import synthetic_record

    x = np.random.default_rng(0).uniform(-3.0, 3.0, 20000)
    h = {}
    h["libm"] = hashlib.sha256(repr([(math.sin(v), math.cos(v), math.atan(v), math.exp(v))
                                     for v in x.tolist()]).encode()).hexdigest()[:12]
    ufuncs = b"".join(f(x).tobytes() for f in (np.sin, np.cos, np.exp, np.arctan))
    h["numpy"] = hashlib.sha256(ufuncs + np.abs(x).sum().tobytes()).hexdigest()[:12]
    M = np.random.default_rng(1).standard_normal((40, 40))
    h["blas"] = hashlib.sha256((M @ M).tobytes() + (M @ M[0]).tobytes() + np.linalg.inv(M[:4, :4]).tobytes()
                               ).hexdigest()[:12]
    h["record"] = hashlib.sha256(synthetic_record(duration=20.0, seed=11)[1].tobytes()).hexdigest()[:12]
    return h


def kernel_env(base: dict | None = None) -> dict:
    """Environment of a process that uses the generic (oldest) kernels instead of this machine's:

    - GLIBC_TUNABLES hides AVX2/FMA from glibc, so libm picks its SSE2 variants of sin, cos, exp, atan, ...
      (the FMA variants round differently in the last bit);
    - OPENBLAS_CORETYPE=Prescott selects OpenBLAS' SSE3 kernels (numpy's and scipy's OpenBLAS);
    - NPY_DISABLE_CPU_FEATURES disables numpy's dispatched SIMD targets, only those this build dispatches
      and this CPU has (numpy refuses to start when asked to disable a feature it does not know)."""
    env = dict(os.environ if base is None else base)
    try:
        from numpy._core import _multiarray_umath as mu
    except ImportError:                                       # numpy < 2
        from numpy.core import _multiarray_umath as mu
    dispatched = [f for f in getattr(mu, "__cpu_dispatch__", []) if mu.__cpu_features__.get(f)]
    if dispatched:
        env["NPY_DISABLE_CPU_FEATURES"] = " ".join(dispatched)
    # glibc >= 2.33 spells the features AVX2, FMA; older glibc AVX2_Usable, FMA_Usable (unknown names
    # are ignored)
    hw = "glibc.cpu.hwcaps=-AVX2,-FMA,-AVX2_Usable,-FMA_Usable"
    env["GLIBC_TUNABLES"] = f"{env['GLIBC_TUNABLES']}:{hw}" if env.get("GLIBC_TUNABLES") else hw
    env["OPENBLAS_CORETYPE"] = "Prescott"
    # one thread: OpenBLAS' idle threads spin and would take the core the suite runs on
    env["OPENBLAS_NUM_THREADS"] = env["OMP_NUM_THREADS"] = "1"
    return env


def kernel_rerun_fixture(keys):
    """A module-scoped pytest fixture ``kernel_rerun``: the scenes ``keys`` re-run in a subprocess under other
    arithmetic kernels, in the background (started by the first test that asks for it, collected by the
    module's test_same_verdicts_under_other_kernels)."""
    import pytest

    @pytest.fixture(scope="module")
    def kernel_rerun():
        rerun = Rerun(sorted(keys))
        yield rerun
        rerun.close()

    return kernel_rerun


class Rerun:
    """Scenes run in a subprocess (by default under `kernel_env`), started at construction so that the
    re-run uses the second core while the suite goes on; `results` waits for them."""

    def __init__(self, keys, env: dict | None = None, seed: int | None = None):
        self.keys = list(keys)
        cmd = [sys.executable, str(Path(__file__).resolve()), "--fingerprint-first"]
        if seed is not None:
            cmd += ["--perturb", str(seed)]
        self.env = kernel_env() if env is None else env
        self.proc = subprocess.Popen(cmd + self.keys, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                     text=True, env=self.env, cwd=str(HERE))
        self._out = None

    def results(self, timeout: float = SUBPROCESS_TIMEOUT) -> dict:
        """{"fingerprint": {...}, key: summary, ...}; raises with the subprocess' stderr if it failed."""
        if self._out is None:
            try:
                out, err = self.proc.communicate(timeout=timeout)
            except subprocess.TimeoutExpired:
                self.close()
                raise AssertionError(f"re-run of {self.keys} took more than {timeout} s") from None
            if self.proc.returncode != 0:
                raise AssertionError(f"re-run of {self.keys} failed ({self.proc.returncode}):\n{err[-3000:]}")
            res = {}
            for line in out.splitlines():
                if line.startswith("{"):
                    d = json.loads(line)
                    res[d.pop("scene")] = d
            self._out = res
        return self._out

    def close(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.communicate()


def main(argv=None) -> int:
    args = list(sys.argv[1:] if argv is None else argv)
    seed = None
    if "--perturb" in args:
        i = args.index("--perturb")
        seed = int(args[i + 1])
        del args[i:i + 2]
    if "--fingerprint" in args:
        print(json.dumps(fingerprint()))
        return 0
    if "--fingerprint-first" in args:
        args.remove("--fingerprint-first")
        print(json.dumps({"scene": "fingerprint", **fingerprint()}), flush=True)
    for key in args:
        _, summ = run_scene(key, Perturbation(seed))
        print(json.dumps({"scene": key, **summ}), flush=True)
    return 0


def check_bounds(figures: dict, bounds: dict, label: str = "") -> None:
    """Assert lo <= figures[name] <= hi for every name: (lo, hi) of ``bounds`` (None: unbounded)."""
    for name, (lo, hi) in bounds.items():
        x = figures[name]
        assert x is not None and (lo is None or x >= lo) and (hi is None or x <= hi), \
            f"{label} {name} = {x!r} outside the documented margin [{lo}, {hi}]"


_FINGERPRINT = None


def assert_kernel_rerun(key: str, rerun: "Rerun", ref: dict, bounds: dict) -> None:
    """The verdict of scene ``key`` re-run under other kernels (``rerun``) equals the nominal one (``ref``,
    the summary of `run_scene`) and its figures stay within ``bounds``; skipped when the other kernels compute
    the same numbers as this machine's defaults (then the re-run proves nothing)."""
    global _FINGERPRINT
    import pytest

    res = rerun.results()
    if _FINGERPRINT is None:
        _FINGERPRINT = fingerprint()
    if res["fingerprint"] == _FINGERPRINT:
        pytest.skip("the generic kernels compute the same numbers as this machine's defaults")
    got = res[key]
    assert got["verdict"] == ref["verdict"], describe_mismatch(got["verdict"], ref["verdict"])
    check_bounds(got["figures"], bounds, f"{key} (other kernels)")


if __name__ == "__main__":
    # run as the module ``roundoff`` (the one the scenes register in), not as __main__
    sys.exit(importlib.import_module("roundoff").main())
