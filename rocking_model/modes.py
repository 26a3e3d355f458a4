"""Contact states: one per contact (`ContactState`), and the contact modes of the two-corner rocking models
(`Mode`: the set of closed corners, whose integer codes are the FMU output ``contact``)."""
from __future__ import annotations

from enum import IntEnum


class ContactState(IntEnum):
    """State of one contact. OPEN: no percussion, the gap may open; CLOSED: at the ground, stuck
    (tangential sliding excluded: the paper's law, the mu -> inf limit). Room is left for the stick / slide
    states of Coulomb friction (issue 15)."""

    OPEN = 0
    CLOSED = 1


def contact_states(closed, n_contacts: int) -> tuple:
    """Per-contact states of the closed set ``closed`` among ``n_contacts`` contacts."""
    s = set(closed)
    return tuple(ContactState.CLOSED if i in s else ContactState.OPEN for i in range(n_contacts))


class Mode(IntEnum):
    """Which base corners touch the ground.

    FULL: both corners closed; LEFT: rocking on the left corner (phi > 0);
    RIGHT: rocking on the right corner (phi < 0); FLIGHT: both corners open.
    """

    FULL = 0
    LEFT = 1
    RIGHT = 2
    FLIGHT = 3


#: what each mode code means (the FMU output ``contact``)
MODE_DESCRIPTIONS = {
    Mode.FULL: "full contact",
    Mode.LEFT: "rocking on the left corner",
    Mode.RIGHT: "rocking on the right corner",
    Mode.FLIGHT: "flight",
}

#: closed contacts (0 = left corner, 1 = right corner) of each mode
CLOSED = {
    Mode.FULL: (0, 1),
    Mode.LEFT: (0,),
    Mode.RIGHT: (1,),
    Mode.FLIGHT: (),
}


def mode_from_closed(closed) -> Mode:
    """The mode whose closed contact set is ``closed`` (an iterable of 0/1)."""
    s = frozenset(closed)
    if s == {0, 1}:
        return Mode.FULL
    if s == {0}:
        return Mode.LEFT
    if s == {1}:
        return Mode.RIGHT
    return Mode.FLIGHT


def pivot_sign(mode: Mode) -> int:
    """s of the pivot corner at body abscissa s*b: -1 left, +1 right."""
    return -1 if mode == Mode.LEFT else 1


class BoundedLog(list):
    """A list that keeps its last ``maxlen`` entries (None: all), trimmed in chunks so that appending stays
    O(1) amortized and memory stays bounded over arbitrarily long runs."""

    #: while True the log is not trimmed (a `Simulator.advance` in progress: on failure the entries it
    #: appended are cut off again, which needs the older ones still there); `release` trims
    held = False

    def __init__(self, maxlen: int | None = None):
        super().__init__()
        self.maxlen = maxlen

    def append(self, item) -> None:
        super().append(item)
        if self.maxlen is not None and len(self) > 2 * self.maxlen and not self.held:
            del self[:len(self) - self.maxlen]

    def hold(self) -> int:
        """Stop trimming (see `held`); returns the current length (to `cut` back to)."""
        self.held = True
        return len(self)

    def release(self) -> None:
        """Trim again (and now, if the log grew past its bound while held)."""
        self.held = False
        if self.maxlen is not None and len(self) > 2 * self.maxlen:
            del self[:len(self) - self.maxlen]

    def cut(self, n: int) -> None:
        """Drop the entries appended since the log had length ``n`` (while held) and release it."""
        del self[n:]
        self.held = False

    def tail(self) -> list:
        """The last ``maxlen`` entries (all when maxlen is None): the chunked trimming keeps up to 2 maxlen."""
        return list(self) if self.maxlen is None else list(self[-self.maxlen:]) if self.maxlen else []

    def __reduce__(self):
        return (bounded_log, (self.maxlen, list(self)))


def bounded_log(maxlen, items) -> BoundedLog:
    """A `BoundedLog` of ``maxlen`` holding ``items`` (trimmed as appending them one by one would)."""
    log = BoundedLog(maxlen)
    log.extend(items)
    return log


_restore_log = bounded_log        # the name pickles of earlier versions refer to
