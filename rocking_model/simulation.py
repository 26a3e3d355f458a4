"""Python API: a stepwise `Simulator` (what the FMUs call) and `simulate()` for whole time histories."""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .ground_motion import ConstantMotion, GroundMotion, as_ground_motion
from .integrators.event_driven import EventDriven
from .integrators.moreau_jean import MoreauJean
from .models.base import RockingModel
from .modes import Mode
from .validation import check_choice, check_real

SCHEMES = {"moreau_jean": "moreau_jean", 0: "moreau_jean", "event_driven": "event_driven", 1: "event_driven"}


class Simulator:
    """One simulation run of ``model`` with the chosen scheme, advanced step by step.

    Parameters
    ----------
    model : RigidBlock or FlexibleOscillator.
    scheme : "moreau_jean" (0) or "event_driven" (1).
    dt_max : [s] Moreau-Jean step (the largest; each `advance` is split in equal steps; default 1e-3 s,
        and at most 0.25/omega for the flexible oscillator), or the largest step of the event-driven scheme
        (default: none). None or 0 selects the scheme's default (0 is how the FMUs spell it).
    tolerance : [1] relative (and scaled absolute) tolerance of the event-driven scheme, in [1e-14, 1e-2].
    theta : [1] Moreau-Jean theta in [0.5, 1].
    zeno_tol : [1] event-driven Zeno rule, v_Zeno = zeno_tol * sqrt(g L).
    method : event-driven Runge-Kutta scheme, "DOP853" (order 8, default) or "DOPRI5" (order 5, cheaper
        at tolerances of 1e-6 and looser).
    impact_log_size : number of impact times kept in ``impact_times`` (None: all; the FMUs keep a bounded
        log so that memory stays flat); ``outputs()["impacts"]`` counts every impact.
    t0 : [s] start time.
    **initial : initial state, passed to ``model.initial_state`` (phi_0 [rad], phi_dot_0 [rad/s], and
        u_0 [m], u_dot_0 [m/s] for the flexible oscillator).
    """

    def __init__(self, model: RockingModel, scheme="event_driven", *, dt_max: float | None = None,
                 tolerance: float = 1e-8, theta: float = 0.5, zeno_tol: float = 1e-6, t0: float = 0.0,
                 method: str = "DOP853", impact_log_size: int | None = 10000, **initial):
        if not isinstance(model, RockingModel):
            raise ValueError(f"model must be a RockingModel (RigidBlock, FlexibleOscillator), got {model!r}")
        self.model = model
        self.scheme = check_choice("scheme", scheme, SCHEMES)
        t0 = check_real("t0", t0)
        mode, q, v = model.initial_state(**initial)
        if impact_log_size is not None:
            impact_log_size = int(check_real("impact_log_size", impact_log_size, lo=0.0))
        dt = check_real("dt_max", dt_max, lo=0.0) if dt_max is not None else 0.0   # 0: the scheme's default
        if self.scheme == "moreau_jean":
            dt = dt or 1e-3
            theta = check_real("theta", theta, lo=0.5, hi=1.0)
            self.integrator = MoreauJean(model, mode, q, v, t0, dt_max=dt, theta=theta,
                                         impact_log_size=impact_log_size)
        else:
            dt = dt or math.inf                                 # uncapped
            tol = check_real("tolerance", tolerance, lo=1e-14, hi=1e-2)
            zt = check_real("zeno_tol", zeno_tol, lo=0.0, hi=1e-2, lo_open=True)
            method = check_choice("method", method, {"DOP853": "DOP853", "DOPRI5": "DOPRI5", "RK45": "DOPRI5",
                                                     0: "DOP853", 1: "DOPRI5"})
            self.integrator = EventDriven(model, mode, q, v, t0, tolerance=tol, dt_max=dt, zeno_tol=zt,
                                          method=method, impact_log_size=impact_log_size)

    @property
    def t(self) -> float:
        """Current time [s]."""
        return self.integrator.t

    @property
    def impact_times(self) -> list[float]:
        """Times of the (last ``impact_log_size``) impacts [s]."""
        return self.integrator.impact_times.tail()

    def advance(self, t_end: float, ag) -> None:
        """Integrate to exactly ``t_end`` [s] under ground acceleration ``ag``: a number [m/s2] held
        constant, a callable ag(t), a (t, ag) pair of arrays or a GroundMotion."""
        t_end = check_real("t_end", t_end)
        if t_end < self.t:
            raise ValueError(f"t_end = {t_end:.17g} is before the current time; allowed range "
                             f"[{self.t:.17g}, inf)")
        self.integrator.advance(t_end, as_ground_motion(ag))

    def state(self) -> tuple[np.ndarray, np.ndarray]:
        """Full generalized coordinates and velocities (q, v)."""
        return self.integrator.state()

    def outputs(self) -> dict:
        """Model outputs plus contact (int), impacts (int) and overturned (bool)."""
        out = self.integrator.outputs()
        out["contact"] = int(self.integrator.mode)
        out["impacts"] = int(self.integrator.impacts)
        out["overturned"] = bool(self.integrator.overturned)
        return out


@dataclass
class Result:
    """Time histories on the output grid: ``t`` and one array per output name; impact times [s]."""

    t: np.ndarray
    values: dict
    impact_times: np.ndarray
    scheme: str
    n_steps: int = 0
    info: dict = field(default_factory=dict)

    def __getitem__(self, name: str) -> np.ndarray:
        return self.t if name == "t" else self.values[name]

    def __getattr__(self, name):
        values = self.__dict__.get("values", {})
        if name in values:
            return values[name]
        raise AttributeError(name)

    def to_csv(self, path) -> None:
        names = list(self.values)
        data = np.column_stack([self.t] + [np.asarray(self.values[n], dtype=float) for n in names])
        np.savetxt(path, data, delimiter=",", header=",".join(["time"] + names), comments="")


def simulate(model: RockingModel, ground_motion=None, t_end: float = 10.0, *, scheme="event_driven",
             output_interval: float = 0.01, hold: str = "exact", **kwargs) -> Result:
    """Simulate ``model`` from t0 to ``t_end`` [s] and return the outputs every ``output_interval`` [s].

    ground_motion: number, callable ag(t), (t, ag) arrays (linear interpolation) or GroundMotion.
    hold: "exact" integrates the ground motion as given; "zoh" holds ag(t_k) constant over each output
        interval, as a co-simulation master (fmpy) does with the FMU.
    Other keyword arguments go to `Simulator` (dt_max, tolerance, theta, zeno_tol, t0, phi_0, ...).
    """
    gm = as_ground_motion(ground_motion)
    hold = check_choice("hold", hold, {"exact": "exact", "zoh": "zoh"})
    kwargs.setdefault("impact_log_size", None)
    sim = Simulator(model, scheme, **kwargs)
    t0 = sim.t
    t_end = check_real("t_end", t_end, lo=t0)
    dt = check_real("output_interval", output_interval, lo=0.0, lo_open=True)
    n = max(1, int(math.ceil((t_end - t0) / dt - 1e-9)))
    # output grid as fmpy builds it: t_k = t0 + k dt, the last one clipped to t_end
    times = np.minimum(t0 + dt * np.arange(n + 1), t_end)
    if hold == "exact" and sim.scheme == "event_driven":
        # one pass through the output grid: the steps are not cut at the output times (dense output), and
        # the outputs are evaluated per contact mode on arrays
        integ = sim.integrator
        samples = [(integ.mode, list(integ.y), integ.impacts, integ.overturned)]
        samples += integ.advance(float(times[-1]), gm, samples=times[1:])
        modes = np.array([int(smp[0]) for smp in samples])
        values = {}
        for mode in np.unique(modes):
            idx = np.nonzero(modes == mode)[0]
            out = sim.model.mode_outputs_array(Mode(int(mode)), np.array([samples[i][1] for i in idx]))
            for name, arr in out.items():
                values.setdefault(name, np.empty(len(samples)))[idx] = arr
        values["contact"] = modes
        values["impacts"] = np.array([smp[2] for smp in samples])
        values["overturned"] = np.array([smp[3] for smp in samples], dtype=bool)
    else:
        records = [sim.outputs()]
        for k in range(n):
            ag = ConstantMotion(gm(times[k])) if hold == "zoh" else gm
            sim.advance(times[k + 1], ag)
            records.append(sim.outputs())
        values = {name: np.array([r[name] for r in records]) for name in records[0]}
    return Result(t=times, values=values, impact_times=np.array(sim.impact_times), scheme=sim.scheme,
                  n_steps=sim.integrator.n_steps)
