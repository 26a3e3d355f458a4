"""What both integrators share about their state: the checks of a loaded plain-data state
(`check_times`, `check_configuration`) and the snapshot an `advance` is rolled back to (`Checkpointed`)."""
from __future__ import annotations

import math


class Checkpointed:
    """Cheap snapshot of an integrator around `Simulator.advance`: `checkpoint` before, then `rollback`
    (restores it exactly) or `commit` (drops it).

    A subclass must replace its attributes, never mutate them in place, except the `BoundedLog` attributes
    named in ``LOGS``: those are held untrimmed while the snapshot lives (`BoundedLog.hold`), so that a
    rollback can cut off what the advance appended."""

    #: names of the BoundedLog attributes
    LOGS: tuple = ()

    def checkpoint(self):
        return self.__dict__.copy(), [getattr(self, name).hold() for name in self.LOGS]

    def rollback(self, snap) -> None:
        d, lengths = snap
        for name, n in zip(self.LOGS, lengths):
            d[name].cut(n)
        self.__dict__.clear()
        self.__dict__.update(d)

    def commit(self, snap) -> None:
        for name, n in zip(self.LOGS, snap[1]):
            log = getattr(self, name)
            if len(log) == n:
                log.held = False          # nothing appended: nothing to trim
            else:
                log.release()


def check_times(state, key, times, t, impacts) -> list:
    """Impact times: at most ``impacts`` of them, non-decreasing, not after t (up to round-off)."""
    if len(times) > impacts:
        raise ValueError(f"state field {key!r} holds {len(times)} impacts, more than impacts = {impacts}")
    t_max = t + 1e-12 * max(1.0, abs(t))
    for i, ti in enumerate(times):
        if ti > t_max or (i and ti < times[i - 1]):
            raise ValueError(f"state field {key!r}: impact time {ti!r} is after t = {t!r} or out of order")
    return times


def check_configuration(model, state, key, q, v, overturned, gap_tol) -> None:
    """The full state (q, v) read from field ``key``: |phi| < pi/2 unless overturned, at rest if overturned,
    corners not below the ground by more than gap_tol [m], and the outputs finite."""
    phi = float(q[model.phi_index])
    if not overturned and not abs(phi) < 0.5 * math.pi:
        raise ValueError(f"state field {key!r}: |phi| = {abs(phi):g} rad reaches pi/2 but 'overturned' is "
                         "False; allowed range (-pi/2, pi/2)")
    if overturned and any(float(a) != 0.0 for a in v):
        raise ValueError(f"state field {key!r}: the velocities must be 0 once 'overturned' is True (the pose "
                         "reached at overturning is kept at rest); got a moving state")
    gaps = model.gaps(q)
    if not overturned and min(gaps) < -gap_tol:
        raise ValueError(f"state field {key!r}: a base corner is {-min(gaps):g} m below the ground; allowed at "
                         f"most {gap_tol:g} m")
    out = model.outputs(q, v)
    bad = [name for name, value in out.items() if not math.isfinite(value)]
    if bad:
        raise ValueError(f"state field {key!r} gives non-finite outputs ({', '.join(bad)}); the values are too "
                         "large for the model")
