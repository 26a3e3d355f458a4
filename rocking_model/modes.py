"""Contact states: one per contact (`ContactState`), and the contact modes of the two-corner rocking models
(`Mode`: the set of closed corners, whose integer codes are the FMU output ``contact``, and `OVERTURNED`, the
code of that output once the structure has overturned)."""
from __future__ import annotations

from enum import IntEnum


class ContactState(IntEnum):
    """State of one contact. OPEN: no percussion, the gap may open; CLOSED: at the ground, stuck
    (tangential sliding excluded: the paper's law, the mu -> inf limit); SLIDE_POS / SLIDE_NEG: at the
    ground, sliding towards +x / -x with the friction force mu lambda_N against it (Coulomb)."""

    OPEN = 0
    CLOSED = 1
    SLIDE_POS = 2
    SLIDE_NEG = 3


def contact_states(closed, n_contacts: int, sigma: int = 0) -> tuple:
    """Per-contact states of the closed set ``closed`` among ``n_contacts`` contacts, sliding in direction
    ``sigma`` (+1, -1; 0: stuck)."""
    s = set(closed)
    on = ContactState.CLOSED if not sigma else ContactState.SLIDE_POS if sigma > 0 else ContactState.SLIDE_NEG
    return tuple(on if i in s else ContactState.OPEN for i in range(n_contacts))


class Mode(IntEnum):
    """Which base corners touch the ground, and whether the base slides.

    FULL: both corners closed; LEFT: rocking on the left corner (phi > 0);
    RIGHT: rocking on the right corner (phi < 0); FLIGHT: both corners open; the corners stick in these.
    FULL_SLIDE_POS, FULL_SLIDE_NEG, LEFT_SLIDE_POS, ...: the same closed corners sliding towards +x / -x
    (Coulomb friction: a finite mu, or the mu -> inf limit where sticking would need tension).
    """

    FULL = 0
    LEFT = 1
    RIGHT = 2
    FLIGHT = 3
    FULL_SLIDE_POS = 4
    FULL_SLIDE_NEG = 5
    LEFT_SLIDE_POS = 6
    LEFT_SLIDE_NEG = 7
    RIGHT_SLIDE_POS = 8
    RIGHT_SLIDE_NEG = 9


#: sliding mode -> (the mode with the same closed corners stuck, the direction sigma of the sliding)
SLIDING = {
    Mode.FULL_SLIDE_POS: (Mode.FULL, 1), Mode.FULL_SLIDE_NEG: (Mode.FULL, -1),
    Mode.LEFT_SLIDE_POS: (Mode.LEFT, 1), Mode.LEFT_SLIDE_NEG: (Mode.LEFT, -1),
    Mode.RIGHT_SLIDE_POS: (Mode.RIGHT, 1), Mode.RIGHT_SLIDE_NEG: (Mode.RIGHT, -1),
}
_SLIDE_OF = {(stick, sigma): mode for mode, (stick, sigma) in SLIDING.items()}

#: what each mode code means (the FMU output ``contact``)
MODE_DESCRIPTIONS = {
    Mode.FULL: "full contact",
    Mode.LEFT: "rocking on the left corner",
    Mode.RIGHT: "rocking on the right corner",
    Mode.FLIGHT: "flight",
    Mode.FULL_SLIDE_POS: "sliding towards +x in full contact",
    Mode.FULL_SLIDE_NEG: "sliding towards -x in full contact",
    Mode.LEFT_SLIDE_POS: "rocking on the left corner sliding towards +x",
    Mode.LEFT_SLIDE_NEG: "rocking on the left corner sliding towards -x",
    Mode.RIGHT_SLIDE_POS: "rocking on the right corner sliding towards +x",
    Mode.RIGHT_SLIDE_NEG: "rocking on the right corner sliding towards -x",
}

#: the code of the output ``contact`` once the structure has overturned (``overturned`` true): not a contact
#: mode (nothing is integrated any more, the outputs are the pose reached at |phi| = pi/2, at rest), so the
#: code after the modes' own; a kept last mode would describe a motion (sliding, rocking) that is not computed
OVERTURNED = 10
OVERTURNED_DESCRIPTION = "overturned (the motion has ended: the pose reached at |phi| = pi/2, at rest)"

#: closed contacts (0 = left corner, 1 = right corner) of each mode
CLOSED = {
    Mode.FULL: (0, 1),
    Mode.LEFT: (0,),
    Mode.RIGHT: (1,),
    Mode.FLIGHT: (),
}
CLOSED.update({mode: CLOSED[stick] for mode, (stick, _) in SLIDING.items()})


def mode_from_closed(closed, sigma: int = 0) -> Mode:
    """The mode whose closed contact set is ``closed`` (an iterable of 0/1), sliding in direction ``sigma``
    (+1, -1; 0: the corners stick)."""
    s = frozenset(closed)
    if s == {0, 1}:
        mode = Mode.FULL
    elif s == {0}:
        mode = Mode.LEFT
    elif s == {1}:
        mode = Mode.RIGHT
    else:
        return Mode.FLIGHT
    return _SLIDE_OF[mode, 1 if sigma > 0 else -1] if sigma else mode


def stick_mode(mode: Mode) -> Mode:
    """The mode with the same closed corners stuck (``mode`` itself if it is not sliding)."""
    return SLIDING[mode][0] if mode in SLIDING else mode


def slide_sign(mode: Mode) -> int:
    """The direction of sliding of ``mode``: +1 towards +x, -1 towards -x, 0 stuck or in flight."""
    return SLIDING[mode][1] if mode in SLIDING else 0


#: the modes that pivot on the left corner
_LEFT = frozenset((Mode.LEFT, Mode.LEFT_SLIDE_POS, Mode.LEFT_SLIDE_NEG))


def pivot_sign(mode: Mode) -> int:
    """s of the pivot corner at body abscissa s*b: -1 left, +1 right."""
    return -1 if mode in _LEFT else 1


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
