"""Siconos' Moreau-Jean time-stepper on the rigid rocking block (peer implementation).

Runs under the interpreter that has Siconos (Debian: python3-siconos under /usr/bin/python3), not in the
project venv; `benchmarks.contenders.run_siconos` starts it as a subprocess:

    /usr/bin/python3 benchmarks/siconos_runner.py job.json result.json

job: {"b", "h", "m", "g", "phi_0", "t_end", "grid", "dts": [...], "repeats", "motion": {...}, "mu", "tmp"}.
(Siconos' solvers print to stdout, hence files.)
Result: {"version", "runs": [{"dt", "times": [...], "phi": [...], "n_steps"}]} or {"error": "..."}.

Model: LagrangianDS q = [x, y, phi], M = diag(m, m, m R^2/3), f_ext = [-m ag, -m g, 0]; one interaction
per base corner, LagrangianScleronomousR with the gap and tangential position as output (compiled C
plugins: Siconos calls relations through plugins; Python-subclassed relations crash 4.4's MoreauJeanOSI),
NewtonImpactFrictionNSL(e_N = 0, e_T = 0, mu) in 2-D, FrictionContact(2) one-step problem with a large
mu so that the contacts stick (the package's sticking law), MoreauJeanOSI(theta = 0.5), TimeStepping.
The ground acceleration is set into f_ext at the mid-step time before each step. The run stops when
|phi| reaches pi/2 (the package's overturning criterion) and phi is frozen from there.
"""
from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import time

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
    for side in ("left", "right"):
        nsl = sk.NewtonImpactFrictionNSL(0.0, 0.0, job["mu"], 2)
        rel = sk.LagrangianScleronomousR(plugin + ":h_" + side, plugin + ":G_" + side)
        inter = sk.Interaction(nsl, rel)
        keep += [nsl, rel, inter]
        nsds.link(inter, ds)
    td = sk.TimeDiscretisation(0.0, dt)
    osi = sk.MoreauJeanOSI(0.5)
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
    phi = [phi0]
    k = 0
    overturned = False
    n_steps = 0
    for i in range(n_grid):
        if overturned:
            phi.append(phi[-1])
            continue
        for _ in range(per):
            F[0] = -m * ag((k + 0.5) * dt)
            sim.computeOneStep()
            sim.nextStep()
            k += 1
            n_steps += 1
            if abs(q[2]) >= 0.5 * math.pi:
                overturned = True
                break
        phi.append(math.copysign(0.5 * math.pi, q[2]) if overturned else float(q[2]))
    elapsed = time.perf_counter() - start
    return elapsed, phi, n_steps


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
        budget = job.get("budget", 3.0)
        for rep in range(job["repeats"]):
            elapsed, phi, n_steps = run_one(job, plugin, dt)
            times.append(elapsed)
            if sum(times) > budget:
                break
        runs.append({"dt": dt, "times": times, "phi": phi, "n_steps": n_steps})
    return {"version": version, "python": sys.version.split()[0], "runs": runs}


if __name__ == "__main__":
    main()
