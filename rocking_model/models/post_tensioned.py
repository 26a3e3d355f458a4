"""Post-tensioned (controlled) rocking block: the rigid block held by an unbonded vertical tendon.

The rigid rocking block (`rocking_model.models.rigid_block`: half-width b [m], half-height h [m], mass m [kg],
its contact laws and outputs) with an unbonded tendon on its centreline, anchored in the ground at the base
centre (0, 0) and in the block at its top centre (body coordinates (0, h), at (0, 2h) at rest). The tendon is
a straight line between its anchors (an unbonded tendon in a wide duct) with axial force

    T = P0 + k_t (L - 2h)   while T >= 0,   0 once slack,

where L [m] is the distance between the anchors, P0 [N] the initial post-tensioning force and k_t [N/m] the
tendon's axial stiffness (E_t A_t / L_t). It acts on the block at its top anchor, along the line to the ground
anchor, with the energy P0 (L - 2h) + k_t (L - 2h)^2 / 2 while taut (the integral of T dL, constant once
slack). Its force is finite: it transmits no impulse, and impacts follow the free block's laws.

Rocking on a corner by phi lengthens the tendon, L(phi) = sqrt(4h^2 + 2b^2 (1 - cos phi) + 4bh |sin phi|),
which adds a restoring moment T dL/dphi; uplift from rest needs |ag| > tan(alpha) (g + ag_v + P0/m). Only after
the base has slid sideways can a tilt back towards the anchor shorten the tendon below 2h and slacken it.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from ..params import Param, param
from .declare import Mechanics, Switch
from .rigid_block import RigidBlock


@dataclass(frozen=True)
class PostTensionedBlock(RigidBlock):
    """Rigid block with a vertical unbonded post-tensioned tendon: b, h [m], m [kg], g [m/s2], e_N [1], P0 [N]
    initial tendon force, k_t [N/m] tendon axial stiffness (P0 = k_t = 0: the free `RigidBlock`).

    Defaults: a precast rocking bridge pier of 1 m x 5 m and 20 t (b = 0.5 m, h = 2.5 m, m = 2e4 kg) with a
    tendon of about 560 mm2 of strand over 5 m (k_t = E_t A_t / L_t = 2e7 N/m) post-tensioned to P0 = 100 kN,
    half the pier's weight: representative values, not a tested specimen. Uplift from rest then needs
    |ag| > tan(alpha) (g + P0/m) = 0.302 g."""

    b: float = param(0.5, "m", "Half-width of the block", lo=1e-6, hi=1e3)
    h: float = param(2.5, "m", "Half-height of the block", lo=1e-6, hi=1e3)
    m: float = param(2e4, "kg", "Mass of the block", lo=1e-9, hi=1e12)
    P0: float = param(1e5, "N", "Initial post-tensioning force of the tendon (>= 0)", lo=0.0, hi=1e15)
    k_t: float = param(2e7, "N/m", "Axial stiffness of the tendon, E_t A_t / L_t (>= 0)", lo=0.0, hi=1e15)

    kind: ClassVar[str] = "post_tensioned"
    fmu_name: ClassVar[str] = "PostTensionedRockingBlock"
    title: ClassVar[str] = "post-tensioned rocking block"

    #: outputs (`outputs`): the block's, the energy including the tendon's, and the tendon force
    OUTPUTS: ClassVar[tuple] = RigidBlock.OUTPUTS[:-1] + (
        Param("energy", 0.0, "J", "Mechanical energy relative to rest (kinetic relative to the ground + "
              "potential + the tendon's P0 (L - 2h) + k_t (L - 2h)^2/2); once overturned, that of the pose reached"),
        Param("tendon_force", 0.0, "N", "Axial force of the tendon, P0 + k_t (L - 2h) while taut, 0 once slack"),
    )

    @staticmethod
    def mechanics(sp, p, q, v) -> Mechanics:
        """The rigid block's mechanics (`RigidBlock.mechanics`) plus the tendon's energy and force."""
        mech = RigidBlock.mechanics(sp, p, q, v)
        x, y, phi = q
        b, h, P0, k_t = p.b, p.h, p.P0, p.k_t
        # the top anchor at body coordinates (0, h); the ground anchor at the origin
        L = sp.sqrt((x - h * sp.sin(phi)) ** 2 + (y + h * sp.cos(phi)) ** 2)
        e = L - 2 * h
        T = P0 + k_t * e
        # slack: the energy stays at its minimum -P0^2/(2 k_t) (reached only when k_t > 0)
        slack = sp.Piecewise((-P0 ** 2 / (2 * k_t), k_t > 0), (0, True))
        mech.potential = sp.Piecewise((P0 * e + k_t * e ** 2 / 2, T >= 0), (slack, True))
        mech.switches = [Switch(T, mech.force_scale, "the tendon slackens or re-tensions")]
        mech.outputs["tendon_force"] = sp.Piecewise((T, T >= 0), (0, True))
        return mech
