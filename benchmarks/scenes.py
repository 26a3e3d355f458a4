"""Benchmark scenes: the models, ground motions, initial conditions and time spans.

Every scene is a plain description (no simulation results), so the same scene can be run by the package,
by the scipy baseline and, through a JSON hand-off, by Siconos under another interpreter.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from rocking_model import SampledMotion, SinePulse
from rocking_model.models import make_model
from rocking_model.records import synthetic_record  # noqa: F401  (moved there; numbers unchanged)

G = 9.81

#: the rigid block of the pulse, free-rocking and record scenes (Housner's 1963 slender block class)
PULSE_BLOCK = dict(b=0.2, h=1.0)        # alpha = 0.197 rad, p = 2.69 rad/s, r = 0.942
FREE_BLOCK = dict(b=0.3, h=1.0)         # alpha = 0.291 rad, r = 0.876: comes to rest within 6 s
RECORD_BLOCK = dict(b=0.4, h=2.0)       # alpha = 0.197 rad, p = 1.92 rad/s: rocks through the record

#: one-sine pulse frequency of the pulse scenes [Hz]
PULSE_F = 2.0
PULSE_BELOW_G = 0.40                    # amplitude below the overturning boundary [g]
PULSE_ABOVE_G = 0.45                    # amplitude above it [g]

#: flexible oscillator: flexural rigidity of the soft and stiff columns [N m2] (default is 9.45e5)
FLEX_SOFT_EI = 9.45e4                   # omega = 12.9 rad/s, omega/p = 5
FLEX_STIFF_EI = 9.45e6                  # omega = 129 rad/s, omega/p = 50
FLEX_PULSE_G = 0.25
FLEX_PULSE_F = 1.5


@dataclass
class Scene:
    """One benchmark case.

    kind: a registered model ("rigid", "flexible"); model_kw: constructor arguments; motion: ("none",), ("sine", A, omega_p)
    or ("sampled", t, ag); initial: initial state (phi_0, ...); t_end [s]; grid: output interval of the
    common comparison grid [s]; mj_dts / ed_tols / base_tols / sic_dts: the sweeps (full run)."""

    name: str
    title: str
    kind: str
    model_kw: dict
    motion: tuple
    t_end: float
    initial: dict = field(default_factory=dict)
    grid: float = 0.01
    mj_dts: tuple = (1e-2, 5e-3, 2e-3, 1e-3, 5e-4, 2e-4)
    ed_tols: tuple = (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11)
    base_tols: tuple = (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11)
    sic_dts: tuple = (1e-2, 5e-3, 2e-3, 1e-3, 5e-4, 2e-4, 1e-4, 5e-5)
    ref_tol: float = 1e-12
    ref_cap: int = 8                      # reference steps capped at grid / ref_cap
    note: str = ""

    def model(self):
        """The scene's model: the registered ``kind`` (`rocking_model.models.MODELS`) with ``model_kw``."""
        return make_model(self.kind, **self.model_kw)

    def ground_motion(self):
        kind = self.motion[0]
        if kind == "none":
            return 0.0
        if kind == "sine":
            return SinePulse(self.motion[1], self.motion[2])
        return SampledMotion(self.motion[1], self.motion[2])

    def motion_json(self) -> dict:
        kind = self.motion[0]
        if kind == "none":
            return {"kind": "none"}
        if kind == "sine":
            return {"kind": "sine", "A": self.motion[1], "omega_p": self.motion[2]}
        return {"kind": "sampled", "t": list(map(float, self.motion[1])), "ag": list(map(float, self.motion[2]))}

    def describe(self) -> str:
        kw = ", ".join(f"{k}={v:g}" for k, v in self.model_kw.items())
        ini = ", ".join(f"{k}={v:g}" for k, v in self.initial.items()) or "at rest"
        kind = self.motion[0]
        if kind == "none":
            gm = "no ground motion"
        elif kind == "sine":
            gm = f"one-sine pulse A = {self.motion[1] / G:.3g} g, f_p = {self.motion[2] / (2 * math.pi):.3g} Hz"
        else:
            a = np.asarray(self.motion[2])
            gm = f"sampled record, {len(a)} samples at {self.motion[1][1] - self.motion[1][0]:g} s, " \
                 f"PGA {np.max(np.abs(a)) / G:.2f} g"
        return f"{self.kind} ({kw}); {gm}; {ini}; T = {self.t_end:g} s"


def rigid_scenes(quick: bool = False) -> list[Scene]:
    w = 2 * math.pi * PULSE_F
    t_rec, a_rec = synthetic_record()
    scenes = [
        Scene("free", "Rigid block, free rocking to rest", "rigid", FREE_BLOCK, ("none",), 7.0,
              initial={"phi_0": 0.15},
              note="released at rest from phi_0 = 0.15 rad (0.52 alpha); impact accumulation ends at ~5.7 s"),
        Scene("pulse_below", "Rigid block, one-sine pulse below overturning", "rigid", PULSE_BLOCK,
              ("sine", PULSE_BELOW_G * G, w), 4.0),
        Scene("pulse_above", "Rigid block, one-sine pulse above overturning", "rigid", PULSE_BLOCK,
              ("sine", PULSE_ABOVE_G * G, w), 4.0),
        Scene("record", "Rigid block, 30 s synthetic record", "rigid", RECORD_BLOCK,
              ("sampled", t_rec, a_rec), 30.0,
              mj_dts=(1e-2, 5e-3, 2e-3, 1e-3),
              base_tols=(1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12)),
    ]
    if quick:
        for s in scenes:
            s.mj_dts = (1e-2, 2e-3)
            s.ed_tols = (1e-4, 1e-8)
            s.base_tols = (1e-4, 1e-8)
            s.sic_dts = (1e-2, 1e-3)
        scenes[0].t_end = 3.0
        scenes[3].t_end = 8.0
        scenes[3].base_tols = (1e-4, 1e-8)
    return scenes


def flexible_scenes(quick: bool = False) -> list[Scene]:
    w = 2 * math.pi * FLEX_PULSE_F
    # reference steps capped at grid/32: with a cap of grid/8 the event-driven scheme misses lift-offs
    # of the flexible oscillator (see the sanity checks in the report)
    scenes = [
        Scene("flex_soft", "Flexible oscillator, soft column, pulse", "flexible", {"EI": FLEX_SOFT_EI},
              ("sine", FLEX_PULSE_G * G, w), 5.0, ref_cap=32),
        Scene("flex_stiff", "Flexible oscillator, stiff column, pulse", "flexible", {"EI": FLEX_STIFF_EI},
              ("sine", FLEX_PULSE_G * G, w), 5.0, ref_cap=32),
    ]
    if quick:
        for s in scenes:
            s.mj_dts = (1e-2, 2e-3)
            s.ed_tols = (1e-4, 1e-8)
            s.t_end = 3.0
    return scenes
