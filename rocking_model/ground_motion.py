"""Ground accelerations: horizontal ag(t) [m/s2], positive in +x, and vertical ag_v(t) [m/s2], positive upward.

A `GroundMotion` is the horizontal component; its ``vertical`` is None (no vertical motion: ag_v = 0) except
for a `TwoComponentMotion`, whose call is the horizontal ag(t) and whose ``vertical`` is another GroundMotion
giving ag_v(t). In the ground frame (the frame of every state and output) ag_v adds the inertial force
-m_i ag_v along +y on every mass m_i: an effective gravity g + ag_v.

Every ground motion is a callable ag(t) that also tells the integrators where it has kinks or jumps
(`next_breakpoint`), so that the event-driven scheme never integrates across one, whether it is
constant (`constant`) and, when known, a bound of |ag| (`peak_bound`), which `Simulator.advance` compares
with `AG_MAX` (1000 m/s2, about 100 g) before any work. Motions without a known bound are checked value by
value as the integrators read them.
"""
from __future__ import annotations

import math
from bisect import bisect_right
from typing import Callable

import numpy as np

from .validation import AG_MAX, check_ag, check_ag_v, check_real

#: the public ground motions (every GroundMotion subclass defined here; all exported by `rocking_model`) and
#: helpers; tests/test_records.py checks that the package exports every public subclass
__all__ = ["GroundMotion", "ConstantMotion", "LinearMotion", "FunctionMotion", "CheckedMotion", "SampledMotion",
           "ScaledMotion", "SinePulse", "CosinePulse", "RickerPulse", "RectangularPulse", "TwoComponentMotion",
           "checked_value", "checked_motion", "pulse_from_parameters", "as_ground_motion", "as_vertical_motion"]


class GroundMotion:
    """Base class: a callable t [s] -> ag [m/s2]."""

    #: True when ag does not depend on t
    constant = False

    #: the vertical component ag_v(t) [m/s2], positive upward: None (zero) except for a `TwoComponentMotion`
    vertical: "GroundMotion | None" = None

    @property
    def horizontal(self) -> "GroundMotion":
        """The horizontal component (this motion itself; a `TwoComponentMotion`'s first component)."""
        return self

    def with_vertical(self, ag_v) -> "TwoComponentMotion":
        """This motion as the horizontal component, with the vertical ground acceleration ``ag_v`` [m/s2],
        positive upward (anything `as_vertical_motion` accepts: a number, a callable, (t, ag_v) arrays or a
        GroundMotion)."""
        return TwoComponentMotion(self, ag_v)

    def __call__(self, t: float) -> float:
        raise NotImplementedError

    def next_breakpoint(self, t: float) -> float:
        """First time > t at which ag is not smooth (math.inf if none)."""
        return math.inf

    def continuous_at(self, tb: float) -> bool:
        """Whether ag is continuous at the breakpoint tb (only its derivative kinks there): the event-driven
        scheme then carries its step on across tb (clipped to it) instead of restarting. Default False (a
        jump: stop, re-decide the contact mode, restart)."""
        return False

    #: (t_start, t_end) [s] outside which ag is zero, or None when unbounded or unknown
    support: tuple[float, float] | None = None

    #: True when __call__ itself refuses values outside [-AG_MAX, AG_MAX] (ValueError naming ag)
    self_checked = False

    @property
    def peak_bound(self) -> float | None:
        """An upper bound of |ag(t)| over all t [m/s2], or None when unknown (then the simulators check
        each value they read)."""
        return None

    def scaled(self, factor: float) -> "GroundMotion":
        """This motion times ``factor`` [1] (same breakpoints)."""
        return ScaledMotion(self, factor)

    def resampled(self, dt: float, t_start: float | None = None, t_end: float | None = None) -> "SampledMotion":
        """Samples every ``dt`` [s] from ``t_start`` to ``t_end`` [s] (default: the support), linear in
        between. No anti-alias filter: a dt coarser than the motion's content cuts its peaks."""
        dt = check_real("dt", dt, lo=0.0, lo_open=True)
        span = self.support
        if t_start is None or t_end is None:
            if span is None:
                raise ValueError(f"{type(self).__name__} has no finite support: give t_start and t_end [s] "
                                 "to resample it")
            t_start = span[0] if t_start is None else t_start
            t_end = span[1] if t_end is None else t_end
        t_start = check_real("t_start", t_start)
        t_end = check_real("t_end", t_end, lo=t_start + dt)
        # grid t_start + k dt; the 1e-9 absorbs round-off so that an exact multiple keeps its last sample
        n = int(math.floor((t_end - t_start) / dt + 1e-9)) + 1
        t = t_start + dt * np.arange(n)
        return SampledMotion(t, [self(float(ti)) for ti in t])


class ConstantMotion(GroundMotion):
    """ag(t) = value (the zero-order hold of a co-simulation step)."""

    constant = True

    def __init__(self, value: float, name: str = "ag"):
        self.value = check_ag(value, name)

    def __call__(self, t):
        return self.value

    @property
    def peak_bound(self):
        return abs(self.value)

    def scaled(self, factor: float) -> "ConstantMotion":
        return ConstantMotion(self.value * check_real("factor", factor))


class LinearMotion(GroundMotion):
    """ag(t) = value + rate (t - t_ref) for t_start <= t <= t_end [s]: the first-order hold of a
    co-simulation step whose master passed the input's derivative (``fmi2SetRealInputDerivatives``). Smooth
    inside the step; its peak over the window is at an end, which the simulators check against AG_MAX."""

    def __init__(self, value: float, rate: float, t_ref: float, t_start: float, t_end: float):
        self.value = check_real("ag", value)
        self.rate = check_real("ag rate", rate)      # [m/s3]
        self.t_ref = check_real("t_ref", t_ref)
        self.window = (check_real("t_start", t_start), check_real("t_end", t_end, lo=t_start))

    def __call__(self, t):
        return self.value + self.rate * (t - self.t_ref)

    @property
    def peak_bound(self):
        return max(abs(self(self.window[0])), abs(self(self.window[1])))

    def scaled(self, factor: float) -> "LinearMotion":
        factor = check_real("factor", factor)
        return LinearMotion(self.value * factor, self.rate * factor, self.t_ref, *self.window)


class FunctionMotion(GroundMotion):
    """Wrap a user callable ag(t); `breakpoints` lists its known kinks [s]. Every value is checked: a value
    that is not a finite number in [-AG_MAX, AG_MAX] raises ValueError naming ag (and the time)."""

    self_checked = True
    #: the variable named in the messages: "ag", or "ag_v" for a vertical component
    name = "ag"

    def __init__(self, fun: Callable[[float], float], breakpoints=(), name: str = "ag"):
        self.fun = fun
        self._bp = np.sort(np.asarray(breakpoints, dtype=float))
        self.name = name

    def __call__(self, t):
        return checked_value(self.fun, t, self.name)

    def next_breakpoint(self, t):
        i = np.searchsorted(self._bp, t, side="right")
        return float(self._bp[i]) if i < self._bp.size else math.inf


def checked_value(fun, t: float, name: str = "ag") -> float:
    """fun(t) as a float in [-AG_MAX, AG_MAX] or ValueError naming ``name`` (ag, or ag_v) and t."""
    try:
        value = float(fun(t))
    except (TypeError, ValueError, OverflowError) as exc:
        raise ValueError(f"{name}({t:.17g}) must be a real number; the ground motion raised "
                         f"{type(exc).__name__}: {exc}") from None
    if -AG_MAX <= value <= AG_MAX:
        return value
    if not math.isfinite(value):
        raise ValueError(f"{name}({t:.17g}) = {value!r} is not finite; allowed range [{-AG_MAX:g}, {AG_MAX:g}] "
                         "m/s2 (AG_MAX)")
    raise ValueError(f"{name}({t:.17g}) = {value:g} is out of range; allowed range [{-AG_MAX:g}, {AG_MAX:g}] "
                     "m/s2 (AG_MAX, about 100 g)")


class CheckedMotion(GroundMotion):
    """A ground motion without a known peak bound, with every value checked (`checked_value`): what the
    simulators run instead of a user's GroundMotion subclass, so that a value out of range stops the step
    with a ValueError naming ag instead of overflowing inside the integrator."""

    self_checked = True
    #: the variable named in the messages: "ag", or "ag_v" for a vertical component
    name = "ag"

    def __init__(self, motion: GroundMotion, name: str = "ag"):
        self.motion = motion
        self.support = motion.support
        self.name = name

    def __call__(self, t):
        return checked_value(self.motion, t, self.name)

    def next_breakpoint(self, t):
        return self.motion.next_breakpoint(t)

    def continuous_at(self, tb):
        return self.motion.continuous_at(tb)


def checked_motion(motion: GroundMotion, name: str = "ag") -> GroundMotion:
    """``motion`` ready for an integrator: refused (ValueError naming ag) when its known peak exceeds
    AG_MAX, wrapped in `CheckedMotion` when its peak is unknown and it does not check its values itself.
    A `TwoComponentMotion` has both components checked (its vertical one's messages name ag_v)."""
    if motion.vertical is not None:
        return TwoComponentMotion(checked_motion(motion.horizontal), checked_motion(motion.vertical, "ag_v"))
    if name != "ag" and isinstance(motion, (FunctionMotion, CheckedMotion)) and motion.name != name:
        # (a user's callable wrapped for the horizontal component: its messages must name this component)
        motion = FunctionMotion(motion.fun, motion._bp, name) if isinstance(motion, FunctionMotion) \
            else CheckedMotion(motion.motion, name)
    peak = motion.peak_bound
    if peak is None:
        return motion if motion.self_checked else CheckedMotion(motion, name)
    if not peak <= AG_MAX:
        raise ValueError(f"{name}: the ground motion's peak |{name}| = {peak:g} m/s2 is out of range; allowed "
                         f"range [{-AG_MAX:g}, {AG_MAX:g}] m/s2 (AG_MAX, about 100 g; check the units of the "
                         "record and its scale factor)")
    return motion


class SampledMotion(GroundMotion):
    """Record sampled at times t [s] (strictly increasing), values ag [m/s2]; linear in between,
    zero outside [t[0], t[-1]]."""

    def __init__(self, t, ag):
        t = np.asarray(t, dtype=float)
        ag = np.asarray(ag, dtype=float)
        if t.ndim != 1 or t.shape != ag.shape or t.size < 2:
            raise ValueError("ground motion: t and ag must be 1-D arrays of equal length >= 2, got shapes "
                             f"{t.shape} and {ag.shape}")
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(ag))):
            raise ValueError("ground motion: t and ag must be finite; allowed range (-inf, inf)")
        if np.any(np.diff(t) <= 0.0):
            raise ValueError("ground motion: t must be strictly increasing")
        self.t, self.ag = t, ag
        self._tl, self._al = t.tolist(), ag.tolist()
        self._i = 0                      # interval of the last evaluation
        self._peak = float(np.max(np.abs(ag)))

    def __call__(self, t):
        tl = self._tl
        # the interval of the last call first (an integrator asks for nearby times), then a bisection
        i = self._i
        if not (tl[i] <= t < tl[i + 1]):
            if t < tl[0] or t > tl[-1]:
                return 0.0
            i = bisect_right(tl, t) - 1
            if i >= len(tl) - 1:
                return self._al[-1]
            self._i = i
        t0, t1 = tl[i], tl[i + 1]
        a0, a1 = self._al[i], self._al[i + 1]
        return a0 + (a1 - a0) * (t - t0) / (t1 - t0)

    def next_breakpoint(self, t):
        i = bisect_right(self._tl, t)
        return self._tl[i] if i < len(self._tl) else math.inf

    def continuous_at(self, tb):
        # linear between the samples: a kink at an inner sample; ag jumps from and to zero at the ends
        tl = self._tl
        return tl[0] < tb < tl[-1]

    @property
    def support(self):
        return (self._tl[0], self._tl[-1])

    @property
    def dt(self) -> float:
        """Mean sample spacing [s]."""
        return (self._tl[-1] - self._tl[0]) / (len(self._tl) - 1)

    @property
    def pga(self) -> float:
        """Peak |ag| over the samples [m/s2]."""
        return self._peak

    @property
    def peak_bound(self):
        # linear interpolation between the samples and zero outside: the samples' peak
        return self._peak

    def scaled(self, factor: float) -> "SampledMotion":
        factor = check_real("factor", factor)
        return SampledMotion(self.t, factor * self.ag)


class ScaledMotion(GroundMotion):
    """``factor`` [1] times another ground motion (same breakpoints and support)."""

    def __init__(self, motion: GroundMotion, factor: float):
        self.motion = as_ground_motion(motion)
        if self.motion.vertical is not None:
            raise ValueError("ScaledMotion takes a single component; scale a TwoComponentMotion with its "
                             "scaled(factor) (both components)")
        self.factor = check_real("factor", factor)
        self.constant = self.motion.constant
        self.support = self.motion.support
        if self.constant:
            self.value = self.factor * self.motion(0.0)   # what the integrators read of a constant motion

    def __call__(self, t):
        return self.factor * self.motion(t)

    @property
    def peak_bound(self):
        peak = self.motion.peak_bound
        return None if peak is None else abs(self.factor) * peak

    def next_breakpoint(self, t):
        return self.motion.next_breakpoint(t)

    def continuous_at(self, tb):
        return self.motion.continuous_at(tb)

    def scaled(self, factor):
        return ScaledMotion(self.motion, self.factor * check_real("factor", factor))


class SinePulse(GroundMotion):
    """One-sine pulse ag = A sin(omega_p (t - t0)) for t0 <= t <= t0 + 2 pi / omega_p, else 0.

    A [m/s2] amplitude, omega_p [rad/s] circular frequency, t0 [s] start."""

    def __init__(self, A: float, omega_p: float, t0: float = 0.0):
        self.A = check_real("A", A)
        self.omega_p = check_real("omega_p", omega_p, lo=0.0, lo_open=True)
        self.t0 = check_real("t0", t0)
        self.t1 = self.t0 + 2.0 * math.pi / self.omega_p

    def __call__(self, t):
        if t < self.t0 or t > self.t1:
            return 0.0
        return self.A * math.sin(self.omega_p * (t - self.t0))

    @property
    def peak_bound(self):
        return abs(self.A)

    def next_breakpoint(self, t):
        for tb in (self.t0, self.t1):
            if tb > t:
                return tb
        return math.inf

    @property
    def support(self):
        return (self.t0, self.t1)

    def scaled(self, factor):
        return SinePulse(self.A * check_real("factor", factor), self.omega_p, self.t0)


#: width of the sliver after a jump [s, relative to max(1, |t|)], see `_jump_breakpoints`
JUMP_SLIVER = 1e-10


def _jump_breakpoints(times) -> list[float]:
    """Breakpoints of jumps at ``times``: each jump time tb and tb + sliver.

    A jump motion takes its left limit at tb and its right value after tb. The integrators evaluate ag at
    both ends of a segment, so the segment ending at tb sees the left limit, the sliver (tb, tb + sliver]
    is the only one that sees a wrong end value (an error ~ sliver * jump), and the segment starting at
    tb + sliver sees the right value. With a single breakpoint the last (or first) Runge-Kutta stage of a
    neighbouring step would use the wrong side, an O(step) error."""
    out = []
    for tb in times:
        out += [tb, tb + JUMP_SLIVER * max(1.0, abs(tb))]
    return sorted(out)


class _JumpBreakpoints:
    _bp: list = []

    def next_breakpoint(self, t):
        for tb in self._bp:
            if tb > t:
                return tb
        return math.inf


class CosinePulse(_JumpBreakpoints, SinePulse):
    """One-cosine pulse ag = A cos(omega_p (t - t0)) for t0 < t <= t0 + 2 pi / omega_p, else 0.

    A [m/s2] amplitude, omega_p [rad/s] circular frequency, t0 [s] start. ag jumps by A at both ends (it
    takes the left limit at each jump time); the ground velocity and displacement return to zero (Makris'
    type-B pulse in acceleration)."""

    def __init__(self, A: float, omega_p: float, t0: float = 0.0):
        super().__init__(A, omega_p, t0)
        self._bp = _jump_breakpoints((self.t0, self.t1))

    def __call__(self, t):
        if t <= self.t0 or t > self.t1:
            return 0.0
        return self.A * math.cos(self.omega_p * (t - self.t0))

    def scaled(self, factor):
        return CosinePulse(self.A * check_real("factor", factor), self.omega_p, self.t0)


class RickerPulse(GroundMotion):
    """Symmetric Ricker wavelet ag = A (1 - w^2 tau^2 / 2) exp(-w^2 tau^2 / 4), tau = t - t_c, w = omega_p.

    A [m/s2] peak (at t_c), omega_p [rad/s] = 2 pi f_p with f_p the peak of the Fourier spectrum, t_c [s]
    centre, default 1.5 T_p (T_p = 2 pi / omega_p) so that |ag(0)| < 1e-8 A. Smooth, no breakpoints; its
    integral (the residual ground velocity) is zero; zeros at tau = +-sqrt(2) / omega_p."""

    def __init__(self, A: float, omega_p: float, t_c: float | None = None):
        self.A = check_real("A", A)
        self.omega_p = check_real("omega_p", omega_p, lo=0.0, lo_open=True)
        T_p = 2.0 * math.pi / self.omega_p
        self.t_c = 1.5 * T_p if t_c is None else check_real("t_c", t_c)
        # ag is below 1e-14 A beyond 2 T_p from the centre: a support for resampling and plots
        self.support = (self.t_c - 2.0 * T_p, self.t_c + 2.0 * T_p)

    def __call__(self, t):
        w = self.omega_p * (t - self.t_c)
        x = 0.25 * (w * w)
        return self.A * (1.0 - 2.0 * x) * math.exp(-x)

    @property
    def peak_bound(self):
        return abs(self.A)        # the peak, at t_c

    def scaled(self, factor):
        return RickerPulse(self.A * check_real("factor", factor), self.omega_p, self.t_c)


class RectangularPulse(_JumpBreakpoints, GroundMotion):
    """Rectangular pulse ag = A for t0 < t <= t0 + duration, else 0 (Housner 1963).

    A [m/s2] amplitude, duration [s] > 0, t0 [s] start; jumps at both ends (left limit at each)."""

    def __init__(self, A: float, duration: float, t0: float = 0.0):
        self.A = check_real("A", A)
        self.duration = check_real("duration", duration, lo=0.0, lo_open=True)
        self.t0 = check_real("t0", t0)
        self.t1 = self.t0 + self.duration
        self.support = (self.t0, self.t1)
        self._bp = _jump_breakpoints((self.t0, self.t1))

    def __call__(self, t):
        return self.A if self.t0 < t <= self.t1 else 0.0

    @property
    def peak_bound(self):
        return abs(self.A)

    def scaled(self, factor):
        return RectangularPulse(self.A * check_real("factor", factor), self.duration, self.t0)


#: pulse kinds of `pulse_from_parameters`
PULSES = ("sine", "cosine", "ricker", "rectangular")


def pulse_from_parameters(kind: str, A: float, omega_p: float | None = None, t_start: float | None = None,
                          duration: float | None = None, scale: float = 1.0) -> GroundMotion:
    """The pulse named by plain parameters: the one factory behind the CLI, the ensembles and the
    GroundMotionSource FMU (identical parameters give identical motions everywhere).

    kind: "sine" (`SinePulse`), "cosine" (`CosinePulse`), "ricker" (`RickerPulse`) or "rectangular"
    (`RectangularPulse`). A [m/s2]: amplitude (peak), multiplied by ``scale`` [1]. omega_p [rad/s] > 0:
    circular frequency (sine, cosine, ricker); for the rectangular pulse it gives the duration 2 pi / omega_p
    when ``duration`` [s] > 0 is not given (give one of the two). t_start [s]: start of the pulse, the centre
    t_c for the Ricker wavelet; None: 0 (Ricker: 1.5 T_p, T_p = 2 pi / omega_p). Raises ValueError naming
    the parameter and its allowed range."""
    if kind not in PULSES:
        raise ValueError(f"pulse = {kind!r} is not supported; allowed values: " + ", ".join(map(repr, PULSES)))
    A = check_real("A", A) * check_real("scale", scale)
    if t_start is not None:
        t_start = check_real("t_start", t_start)
    if omega_p is not None:
        omega_p = check_real("omega_p", omega_p, lo=0.0, lo_open=True)
    if kind == "rectangular":
        if (duration is None) == (omega_p is None):
            raise ValueError("a rectangular pulse needs either duration [s] (allowed range (0, inf)) or omega_p "
                             "[rad/s] (duration 2 pi / omega_p), not " + ("both" if omega_p is not None else "neither"))
        if duration is None:
            duration = 2.0 * math.pi / omega_p
        duration = check_real("duration", duration, lo=0.0, lo_open=True)
        return RectangularPulse(A, duration, 0.0 if t_start is None else t_start)
    if duration is not None:
        raise ValueError(f"duration = {duration!r} applies to the rectangular pulse only; a {kind} pulse lasts "
                         "2 pi / omega_p")
    if omega_p is None:
        raise ValueError(f"a {kind} pulse needs omega_p [rad/s]; allowed range (0, inf)")
    if kind == "ricker":
        return RickerPulse(A, omega_p, t_start)
    cls = SinePulse if kind == "sine" else CosinePulse
    return cls(A, omega_p, 0.0 if t_start is None else t_start)


def _has_breakpoint(motion: GroundMotion, tb: float) -> bool:
    """Whether ``tb`` is one of ``motion``'s breakpoints (the first one after the float just below it)."""
    return motion.next_breakpoint(math.nextafter(tb, -math.inf)) == tb


class TwoComponentMotion(GroundMotion):
    """A horizontal ground acceleration ag(t) [m/s2] (positive along +x) with a vertical one ag_v(t) [m/s2]
    (positive upward): the call is the horizontal ag(t), ``vertical(t)`` is ag_v(t).

    Both components are GroundMotions (anything `as_ground_motion` / `as_vertical_motion` accepts is
    converted). ``next_breakpoint`` is the earlier of both components', so that the integrators stop at the
    breakpoints of either; ``continuous_at(tb)`` holds where both are continuous (a component without a
    breakpoint at tb is continuous there); ``constant`` where both are (``value``: the horizontal value);
    ``peak_bound`` is the horizontal one's (the vertical is checked by `checked_motion` on its own, naming
    ag_v); ``support`` the hull of both supports (None if either is unbounded or unknown)."""

    def __init__(self, horizontal, vertical):
        h = as_ground_motion(horizontal)
        v = as_vertical_motion(vertical)
        if h.vertical is not None or v.vertical is not None:
            raise ValueError("ag_v: a TwoComponentMotion's components must be single (horizontal or vertical) "
                             "ground motions; got a component that already has a vertical part")
        self._horizontal = h
        self.vertical = v
        self.constant = bool(h.constant and v.constant)
        if self.constant:
            self.value = h.value if hasattr(h, "value") else h(0.0)
        self.self_checked = bool(h.self_checked)

    @property
    def horizontal(self) -> GroundMotion:
        return self._horizontal

    def __call__(self, t):
        return self._horizontal(t)

    def next_breakpoint(self, t):
        a = self._horizontal.next_breakpoint(t)
        b = self.vertical.next_breakpoint(t)
        return a if a < b else b

    def continuous_at(self, tb):
        return all(not _has_breakpoint(c, tb) or c.continuous_at(tb) for c in (self._horizontal, self.vertical))

    @property
    def peak_bound(self):
        return self._horizontal.peak_bound

    @property
    def support(self):
        a, b = self._horizontal.support, self.vertical.support
        if a is None or b is None:
            return None
        return (min(a[0], b[0]), max(a[1], b[1]))

    def scaled(self, factor: float) -> "TwoComponentMotion":
        """Both components times ``factor`` [1]."""
        return TwoComponentMotion(self._horizontal.scaled(factor), self.vertical.scaled(factor))

    def resampled(self, dt: float, t_start: float | None = None, t_end: float | None = None) -> "TwoComponentMotion":
        """Both components sampled on the same grid (see `GroundMotion.resampled`; default span: the hull of
        both supports)."""
        span = self.support
        if (t_start is None or t_end is None) and span is None:
            raise ValueError("TwoComponentMotion has no finite support: give t_start and t_end [s] to resample it")
        t_start = span[0] if t_start is None else t_start
        t_end = span[1] if t_end is None else t_end
        return TwoComponentMotion(self._horizontal.resampled(dt, t_start, t_end),
                                  self.vertical.resampled(dt, t_start, t_end))

    def __repr__(self):
        return f"TwoComponentMotion({self._horizontal!r}, {self.vertical!r})"


def as_vertical_motion(ag_v) -> GroundMotion:
    """The vertical ground acceleration ag_v [m/s2], positive upward, as a GroundMotion: a number (checked,
    |ag_v| <= AG_MAX), a callable ag_v(t) (values checked, messages naming ag_v), a (t, ag_v) pair of arrays
    or a GroundMotion without a vertical part of its own."""
    if isinstance(ag_v, GroundMotion):
        if ag_v.vertical is not None:
            raise ValueError("ag_v must be a single (vertical) ground motion, got a TwoComponentMotion")
        return ag_v
    if isinstance(ag_v, (int, float)) and not isinstance(ag_v, bool):
        return ConstantMotion(check_ag_v(ag_v), "ag_v")
    if callable(ag_v):
        return FunctionMotion(ag_v, name="ag_v")
    if isinstance(ag_v, (tuple, list)) and len(ag_v) == 2:
        t, a = np.asarray(ag_v[0], dtype=float), np.asarray(ag_v[1], dtype=float)
        if a.shape == t.shape and not np.all(np.isfinite(a)):
            raise ValueError("ag_v: the vertical record's values must be finite; allowed range "
                             f"[{-AG_MAX:g}, {AG_MAX:g}] m/s2")
        return SampledMotion(t, a)
    try:
        return ConstantMotion(check_ag_v(ag_v), "ag_v")        # numpy scalars and other real numbers
    except ValueError:
        pass
    raise ValueError("ag_v must be a number, a callable ag_v(t), a (t, ag_v) pair of arrays or a GroundMotion, "
                     f"got {type(ag_v).__name__}")


def as_ground_motion(ag) -> GroundMotion:
    """Accept a GroundMotion, a number, a callable, a (t, ag) pair of arrays; for two components a pair of
    callables (ag(t), ag_v(t)) or three arrays (t, ag, ag_v) (both sampled on t), giving a
    `TwoComponentMotion` (ag_v [m/s2] positive upward)."""
    if isinstance(ag, GroundMotion):
        return ag
    if ag is None:
        return ConstantMotion(0.0)
    if isinstance(ag, (int, float)):
        return ConstantMotion(ag)
    if callable(ag):
        return FunctionMotion(ag)
    if isinstance(ag, (tuple, list)) and len(ag) == 2:
        if callable(ag[0]) and callable(ag[1]):
            return TwoComponentMotion(ag[0], ag[1])
        return SampledMotion(*ag)
    if isinstance(ag, (tuple, list)) and len(ag) == 3:
        t, a, a_v = ag
        t = np.asarray(t, dtype=float)
        return TwoComponentMotion(SampledMotion(t, a), as_vertical_motion((t, a_v)))
    raise ValueError("ground_motion must be a number, a callable ag(t), a (t, ag) pair of arrays, a pair of "
                     "callables (ag(t), ag_v(t)), three arrays (t, ag, ag_v) or a GroundMotion, got "
                     f"{type(ag).__name__}")
