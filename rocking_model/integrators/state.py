"""What both schemes share about their state: the check of a loaded plain-data state's impact times
(`check_times`) and the snapshot an `advance` is rolled back to (`Checkpointed`)."""
from __future__ import annotations



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
