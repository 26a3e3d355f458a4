"""Siconos' Moreau-Jean time-stepper on the rigid rocking block (peer implementation).

Runs under the interpreter that has Siconos (Debian: python3-siconos under /usr/bin/python3), not in the
project venv; `benchmarks.contenders.run_siconos` starts it as a subprocess:

    /usr/bin/python3 benchmarks/siconos_runner.py job.json result.json

job: {"b", "h", "m", "g", "phi_0", "t_end", "grid", "dts": [...], "repeats", "motion": {...}, "mu", "tmp"}
(motion: {"kind": "none"}, {"kind": "constant", "A"}, {"kind": "sine", "A", "omega_p"} or {"kind": "sampled",
"t": [...], "ag": [...]}) and optionally "solver" ("lemke", the default, or "nsgs"), "e_N" (0 by default),
"budget", "ag_rule" ("midpoint", the default: ag at t + dt/2; "trapezoid": (ag(t) + ag(t + dt)) / 2, the
package's theta-weighted forcing at theta = 1/2) and "activation_threshold" [m] (MoreauJeanOSI's, 0 by
default). (Siconos' solvers print to stdout, hence files.)
Result: {"version", "mu_used", "runs": [{"dt", "times": [...], "phi": [...], "n_steps", "x": [...],
"x_dot": [...], "y": [...], "phi_dot": [...], "contact": [...]}]} or {"error": "..."}; the per-time lists are
on the output grid (t = 0, grid, 2 grid, ...), x and y are the centroid's displacement from rest relative to
the ground (the package's outputs x and y), contact the package's mode code (rocking_model.modes.Mode: 0 both
corners, 1 left, 2 right, 3 none; 4..9 the same closed corners sliding towards +x / -x) of the corners that
carried a normal impulse in the step that ended there.

Model: LagrangianDS q = [x, y, phi], M = diag(m, m, m R^2/3), f_ext = [-m ag, -m g, 0]; one interaction
per base corner, LagrangianScleronomousR with the gap and tangential position as output (compiled C
plugins: Siconos calls relations through plugins; Python-subclassed relations crash 4.4's MoreauJeanOSI),
NewtonImpactFrictionNSL(e_N, e_T = 0, mu) in 2-D, FrictionContact(2) one-step problem, MoreauJeanOSI(theta =
0.5), TimeStepping. A finite job mu is used unchanged (Coulomb friction); mu = inf (JSON Infinity, null or
missing) stands for the package's sticking law and is replaced by STICK_MU, large enough that the contacts
stick.
The ground acceleration is set into f_ext before each step (per "ag_rule"). The run stops when
|phi| reaches pi/2 (the package's overturning criterion) and phi is frozen from there.
"""
from __future__ import annotations

import gc
import json
import math
import os
import subprocess
import sys
import time

#: Coulomb coefficient standing for the sticking law (job mu = inf or missing)
STICK_MU = 100.0
#: [m/s] a closed corner with a larger tangential velocity after the step slides (contact codes 4..9)
SLIP_TOL = 1e-9


def friction_mu(job) -> float:
    """The mu given to NewtonImpactFrictionNSL: the job's finite mu unchanged, STICK_MU for inf/missing."""
    mu = job.get("mu")
    if mu is None or (isinstance(mu, str) and mu.strip().lower() in ("inf", "infinity")):
        return STICK_MU
    mu = float(mu)
    if not mu > 0.0:
        raise ValueError(f"mu = {mu!r}: must be > 0")
    return mu if math.isfinite(mu) else STICK_MU

PLUGIN_C = r"""
#include <math.h>
static void hs(double s, const double* q, double* y, unsigned ny) {
  double yy[2];
  yy[0] = q[1] + s * BB * sin(q[2]) - HH * cos(q[2]);
  yy[1] = q[0] + s * BB * (cos(q[2]) - 1.0) + HH * sin(q[2]);
  for (unsigned i = 0; i < ny; i++) y[i] = yy[i];
}
static void Js(double s, const double* q, double* J, unsigned ny) {   /* column-major ny x 3 */
  double sp = sin(q[2]), cp = cos(q[2]);
  if (ny == 1) { J[0] = 0; J[1] = 1; J[2] = s * BB * cp + HH * sp; return; }
  J[0] = 0; J[1] = 1; J[2] = 1; J[3] = 0; J[4] = s * BB * cp + HH * sp; J[5] = -s * BB * sp + HH * cp;
}
void h_left(unsigned nq, double* q, unsigned ny, double* y, unsigned nz, double* z) { hs(-1.0, q, y, ny); }
void h_right(unsigned nq, double* q, unsigned ny, double* y, unsigned nz, double* z) { hs(1.0, q, y, ny); }
void G_left(unsigned nq, double* q, unsigned ny, double* J, unsigned nz, double* z) { Js(-1.0, q, J, ny); }
void G_right(unsigned nq, double* q, unsigned ny, double* J, unsigned nz, double* z) { Js(1.0, q, J, ny); }
"""


def build_plugin(b, h, tmp):
    src = os.path.join(tmp, "rockplug.c")
    lib = os.path.join(tmp, "rockplug.so")
    with open(src, "w") as f:
        f.write(PLUGIN_C)
    subprocess.run(["gcc", "-O2", "-shared", "-fPIC", f"-DBB={b!r}", f"-DHH={h!r}", "-o", lib, src, "-lm"],
                   check=True, capture_output=True)
    return os.path.join(tmp, "rockplug")


def make_ag(motion):
    kind = motion["kind"]
    if kind == "none":
        return lambda t: 0.0
    if kind == "constant":
        A = float(motion["A"])
        return lambda t: A
    if kind == "sine":
        A, w = motion["A"], motion["omega_p"]
        t1 = 2 * math.pi / w
        return lambda t: A * math.sin(w * t) if 0.0 <= t <= t1 else 0.0
    import numpy as np
    ts, a = np.asarray(motion["t"]), np.asarray(motion["ag"])
    return lambda t: float(np.interp(t, ts, a, left=0.0, right=0.0))


def run_one(job, plugin, dt):
    import numpy as np
    import siconos.kernel as sk
    import siconos.numerics as sn

    b, h, m, g = job["b"], job["h"], job["m"], job["g"]
    R = math.hypot(b, h)
    phi0 = job["phi_0"]
    s = -1.0 if phi0 >= 0 else 1.0
    if phi0 == 0.0:
        q0 = np.array([0.0, h, 0.0])
    else:
        q0 = np.array([s * b * (1 - math.cos(phi0)) - h * math.sin(phi0), -s * b * math.sin(phi0) + h * math.cos(phi0),
                       phi0])
    ag = make_ag(job["motion"])
    t_end, grid = job["t_end"], job["grid"]
    n_grid = int(round(t_end / grid))
    per = int(round(grid / dt))
    start = time.perf_counter()
    ds = sk.LagrangianDS(q0, np.zeros(3), np.diag([m, m, m * R * R / 3.0]))
    fext = np.array([0.0, -m * g, 0.0])
    ds.setFExtPtr(fext)
    nsds = sk.NonSmoothDynamicalSystem(0.0, t_end)
    nsds.insertDynamicalSystem(ds)
    keep = []
    mu = friction_mu(job)
    e_N = float(job.get("e_N", 0.0))
    inters = []
    for side in ("left", "right"):
        nsl = sk.NewtonImpactFrictionNSL(e_N, 0.0, mu, 2)
        rel = sk.LagrangianScleronomousR(plugin + ":h_" + side, plugin + ":G_" + side)
        inter = sk.Interaction(nsl, rel)
        keep += [nsl, rel, inter]
        inters.append(inter)
        nsds.link(inter, ds)
    td = sk.TimeDiscretisation(0.0, dt)
    osi = sk.MoreauJeanOSI(0.5)
    if job.get("activation_threshold"):
        # a corner enters the step's problem when y + dt/2 y_dot <= threshold (Siconos' default 0: a corner
        # resting at gap 0 drops out on a round-off positive normal velocity)
        osi.setConstraintActivationThreshold(float(job["activation_threshold"]))
    solver = job.get("solver", "lemke")
    if solver == "lemke":       # 2-D friction as an LCP, solved by pivoting: exact for these 2-contact problems
        osnspb = sk.FrictionContact(2, sn.SICONOS_FRICTION_2D_LEMKE)
    else:                       # Siconos' default 2-D solver (NSGS), tightened
        osnspb = sk.FrictionContact(2)
        osnspb.numericsSolverOptions().dparam[sn.SICONOS_DPARAM_TOL] = 1e-12
        osnspb.numericsSolverOptions().iparam[sn.SICONOS_IPARAM_MAX_ITER] = 1000
    sim = sk.TimeStepping(nsds, td, osi, osnspb)
    F = ds.fExt()
    q = ds.q()
    v = ds.velocity()
    trapezoid = job.get("ag_rule", "midpoint") == "trapezoid"
    phi = [phi0]
    out = {"x": [float(q[0])], "y": [float(q[1]) - h], "x_dot": [0.0], "phi_dot": [0.0],
           "contact": [0 if phi0 == 0.0 else (1 if phi0 > 0 else 2)]}

    def record(phi_pred):
        closed = [float(inter.lambda_(1)[0]) > 0.0 for inter in inters]
        code = {(True, True): 0, (True, False): 1, (False, True): 2, (False, False): 3}[tuple(closed)]
        # sliding: a closed corner whose post-step tangential velocity is not zero (Lemke gives round-off
        # zeros when it sticks); the package's codes 4..9 (FULL/LEFT/RIGHT sliding towards +x, -x). The
        # velocity is taken with the Jacobian of the step's problem: MoreauJeanOSI evaluates it at the
        # predicted position q_k + dt v_k (phi_pred here; checked: the sticking pivot's velocity is then 0 to
        # round-off), while its output y(1) uses q_k+1 and differs from the complementarity velocity by O(dt^2)
        sp, cp = math.sin(phi_pred), math.cos(phi_pred)
        slip = [float(v[0]) + (-sgn * b * sp + h * cp) * float(v[2])
                for sgn, c in zip((-1.0, 1.0), closed) if c]
        u_T = max(slip, key=abs) if slip else 0.0
        if code != 3 and abs(u_T) > SLIP_TOL:
            code = 4 + 2 * code + (0 if u_T > 0.0 else 1)
        out["contact"].append(code)
        out["x"].append(float(q[0]))
        out["y"].append(float(q[1]) - h)
        out["x_dot"].append(float(v[0]))
        out["phi_dot"].append(float(v[2]))

    k = 0
    overturned = False
    n_steps = 0
    phi_pred = phi0
    for i in range(n_grid):
        if overturned:
            phi.append(phi[-1])
            for key in out:
                out[key].append(out[key][-1])
            continue
        for j in range(per):
            if j == per - 1:
                phi_pred = float(q[2]) + dt * float(v[2])
            F[0] = -m * (0.5 * (ag(k * dt) + ag((k + 1) * dt)) if trapezoid else ag((k + 0.5) * dt))
            sim.computeOneStep()
            sim.nextStep()
            k += 1
            n_steps += 1
            if abs(q[2]) >= 0.5 * math.pi:
                overturned = True
                break
        phi.append(math.copysign(0.5 * math.pi, q[2]) if overturned else float(q[2]))
        record(phi_pred)
    elapsed = time.perf_counter() - start
    return elapsed, phi, n_steps, out


def main():
    with open(sys.argv[1]) as f:
        job = json.load(f)
    with open(sys.argv[2], "w") as out:
        json.dump(_run(job), out)


def _run(job):
    try:
        import siconos  # noqa: F401
        import siconos.kernel  # noqa: F401
    except Exception as exc:  # pragma: no cover - depends on the machine
        return {"error": f"siconos not importable: {exc}"}
    try:
        friction_mu(job)
    except (TypeError, ValueError) as exc:
        return {"error": f"bad job mu: {exc}"}
    try:
        plugin = build_plugin(job["b"], job["h"], job["tmp"])
    except Exception as exc:
        return {"error": f"cannot compile the relation plugin with gcc: {exc}"}
    try:
        version = subprocess.run(["dpkg-query", "-W", "-f=${Version}", "python3-siconos"], capture_output=True,
                                 text=True).stdout.strip() or "unknown"
    except Exception:
        version = "unknown"
    runs = []
    for dt in job["dts"]:
        times = []
        phi = n_steps = None
        out = {}
        budget = job.get("budget", 3.0)
        # timed as the other contenders (contenders.timed, timeit's practice): gc off during each run, repeats
        # until min_total seconds (at least `repeats`), none started past the budget; the caller takes the minimum
        enabled = gc.isenabled()
        while True:
            gc.disable()
            try:
                elapsed, phi, n_steps, out = run_one(job, plugin, dt)
            finally:
                if enabled:
                    gc.enable()
            times.append(elapsed)
            if sum(times) > budget or (len(times) >= max(1, job["repeats"]) and sum(times) >= job.get("min_total", 0.0)):
                break
        runs.append({"dt": dt, "times": times, "phi": phi, "n_steps": n_steps, **out})
    return {"version": version, "python": sys.version.split()[0], "mu_used": friction_mu(job), "runs": runs}


if __name__ == "__main__":
    main()
