"""The numerical thresholds of the contact handling, named once, each with its reason and its unit.

Both schemes read them from one `ContactTolerances` (`Simulator(..., tolerances=...)`), in the Python reference
and in the compiled engine alike (each field's comment names the scheme that reads it); the defaults are
what every published figure of this package was computed with. Relative values are scaled by the model's
length scale L [m] (`RockingModel.length_scale`: R = sqrt(b^2 + h^2) for the rigid block, sqrt(b^2 + h^2) of
base half-width and column height for the flexible oscillator), its velocity scale sqrt(g L) [m/s] or its time
scale 1/p [s] (`for_model`).

Why the two schemes use different values for what looks like one notion:

- *At the ground.* The event-driven scheme locates events to round-off in time, so a corner it declares
  closed sits at the ground up to the root finder's residual in the gap function, some 1e-12 L to 1e-10 L:
  ``gap`` = 1e-9 L is a safe margin above that and far below any physical gap. The time-stepper
  (Moreau-Jean) projects closed corners onto the ground exactly up to the last bits (`project_to_ground`),
  and its candidate test ``g + dt/2 U <= margin`` must not catch corners that are merely about to close:
  ``step_gap`` = 1e-12 L is round-off of the projection only.
- *At rest in the normal direction.* After an event the normal velocity of a closed corner is zero up to
  round-off of the impact LCP (1e-14 to 1e-12 sqrt(g L)): ``rest_velocity`` = 1e-10 sqrt(g L). A
  Moreau-Jean step leaves O(dt * |f| / m) of residual velocity on corners it keeps closed through the
  theta-method's force average; ``step_rest_velocity`` = 1e-9 sqrt(g L) separates that from an approach
  that is an impact (the slowest impact of a rocking block at rest-tilt energies is some 1e-4 sqrt(g L)).

The contact LCPs (the engine's `rk_lcp.c`, through `rk_contact.c`) of both schemes take the user's
``lcp_exact`` and ``lcp_hint``: the event-driven scheme's impact LCP (and its Zeno re-solves), uplift LCP
(`contact.next_mode`, the mode after every event) and Painleve impact LCP; Moreau-Jean's step LCP.
``lcp_exact`` tells an exact solution (an inexact one is reported, `inexact_contact`; with mu = inf the
sticking LCP's mu -> inf limit is tried where it is inexact); with friction it also picks the solution (the
first state combination, in the order of preference, that violates the conditions by less than it) and counts
them (Painleve). ``lcp_hint`` applies where a hint is given: Moreau-Jean's last closed set (taken within it, it
is still exact only within ``lcp_exact``); the event-driven scheme gives none. The forces of a mode held closed
(`contact.mode_forces`) take neither: all its contacts are forced, one active set.

The Zeno rule (event-driven: the end of an impact accumulation; docs/guide/schemes.md, "Impact accumulation
(Zeno)") has two tests, applied after every impact to the corners at the ground, with two thresholds:

- *velocity test*: a corner whose post-impact separation velocity U_N+ is below v_Zeno = zeno_tol sqrt(g L) is
  closed; ``zeno_tol`` [1] is a solver setting (`ZENO_TOL` by default: 3.2e-6 m/s for the 0.2 x 1.0 m block);
- *bounce test*, only while every corner leaves (free flight) and none is closed: the corner with the lowest
  free-flight bounce U_N+^2 / (2 |a_N|) (a_N < 0 its normal acceleration in flight, about -g) is closed if that
  bounce is below ``gap`` (1e-9 L), i.e. if U_N+ < sqrt(2 |a_N| gap) = sqrt(2e-9) sqrt(g L) at |a_N| = g:
  44.7 v_Zeno at the default zeno_tol.

A closed corner is held closed plastically (the impact LCP is solved again from the pre-impact velocities) and
both tests are applied again to the new outcome: a corner that leaves while another is closed rotates about
it (its normal acceleration is the rocking one, 2 b p^2 sin(alpha) for the block, not g) and only the velocity
test applies to it. A corner closed within ``gap`` above the ground becomes the pivot of a rocking mode exactly
at the ground: the event-driven scheme then projects the state onto the ground (that corner and any the
reduction would put below it), so no mode starts with an open corner below the ground beyond round-off
(``grazing`` ``gap``) and every open corner's event function starts armed or watched.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, fields


#: [1] default of the event-driven setting ``zeno_tol``: the Zeno rule's velocity test closes a corner that
#: leaves slower than v_Zeno = zeno_tol sqrt(g L) (module docstring). Far above the impact LCP's round-off
#: (``rest_velocity``, 1e-10), far below the slowest impact that matters: a block rocking at v_Zeno / (2 b)
#: has an amplitude of some 2e-11 rad
ZENO_TOL = 1e-6


@dataclass(frozen=True)
class ContactTolerances:
    """Thresholds of contact detection, event location and contact solves (see the module docstring).

    Each field: value, unit, reason. "[L]" means relative to the model's length scale, "[sqrt(gL)]" to its
    velocity scale, "[1/p]" to its time scale; "[1]" is a pure number.
    """

    #: [L] event-driven: a corner within this of the ground counts as at the ground (candidate of the
    #: contact LCPs); above the root finder's residual (1e-12 to 1e-10 L), far below any physical gap. Also the
    #: Zeno rule's bounce test: a free-flight bounce that would stay within it is closed (module docstring)
    gap: float = 1e-9
    #: [L] Moreau-Jean: round-off margin of the candidate test g + dt/2 U <= step_gap for corners just
    #: projected onto the ground (the projection is exact to the last bits)
    step_gap: float = 1e-12
    #: [gap] event-driven: a corner found lower than this below the ground at an impact is a grazing landing
    #: (it never rose measurably above round-off) and is put back onto the ground
    grazing: float = 1e-3
    #: [sqrt(gL)] event-driven: a normal velocity below this counts as zero (round-off of the impact LCP)
    rest_velocity: float = 1e-10
    #: [sqrt(gL)] Moreau-Jean: a closing corner slower than this is not an impact, and two closed corners
    #: this slow are at rest (residual velocity of the theta-method's force average)
    step_rest_velocity: float = 1e-9
    #: [1] event-driven: how far below zero a disarmed (normalised) event function may go before it fires
    #: (a grazing entry that turns back); event functions are O(1) at their scale, so 1e-10 is round-off
    #: grown over a few steps
    event: float = 1e-10
    #: [event] event-driven: level above zero at which a corner that starts a segment at the ground counts
    #: as risen (a short bounce), a thousandth of ``event`` so that a bounce above round-off is not missed
    rise: float = 1e-3
    #: [1] event-driven: an open corner whose normalised opening exceeds this is clearly open, so the active
    #: set of a mode change is kept without solving the uplift LCP (a fast path: the LCP decides below it)
    clearly_open: float = 1e-9
    #: [1/p] event-driven: longest step of a phase without state (rigid block in full contact): only the
    #: contact forces move, under a varying input; the dip search must see a force that comes and goes
    stateless_step: float = 0.1
    #: [1] event-driven: sub-intervals a step is cut into when a contact function may dip below zero and
    #: come back within it (the dip and earlier-event searches)
    sub_samples: int = 16
    #: [1] contact LCPs of both schemes: a solution violating the conditions by less than this (relative to the
    #: problem's scales) is exact; above it the least-violating active set is returned and reported as inexact
    #: (with friction: the first combination of contact states within it is taken; module docstring)
    lcp_exact: float = 1e-9
    #: [1] Moreau-Jean's step LCP: violation below which the time-stepper's last active set is taken without
    #: enumerating the others (round-off of a persistent contact); the event-driven scheme has no such hint
    lcp_hint: float = 1e-12
    #: [weight] friction demand (both schemes): a total normal force (or per time-step percussion over the step)
    #: below this fraction of the weight carries no load, so the ratio |lambda_T| / lambda_N there is round-off
    #: over round-off and is not counted; near a lift-off the demand therefore grows to at most ~1/demand_floor
    demand_floor: float = 1e-6

    def __post_init__(self):
        for f in fields(self):
            value = getattr(self, f.name)
            if f.name == "sub_samples":
                if not isinstance(value, int) or isinstance(value, bool) or not 2 <= value <= 1024:
                    raise ValueError(f"tolerances.sub_samples = {value!r} is out of range; allowed range "
                                     "[2, 1024] (an integer)")
            elif not (isinstance(value, (int, float)) and not isinstance(value, bool)
                      and math.isfinite(value) and 0.0 < value < 1.0):
                raise ValueError(f"tolerances.{f.name} = {value!r} is out of range; allowed range (0, 1)")

    def for_model(self, model) -> "ModelTolerances":
        """The absolute thresholds for ``model`` (its length, velocity and time scales)."""
        L = model.length_scale
        V = math.sqrt(model.g * L)
        return ModelTolerances(gap=self.gap * L, step_gap=self.step_gap * L, rest_velocity=self.rest_velocity * V,
                               step_rest_velocity=self.step_rest_velocity * V,
                               stateless_step=self.stateless_step * model.time_scale, velocity_scale=V,
                               force_floor=self.demand_floor * model.force_scale)


@dataclass(frozen=True)
class ModelTolerances:
    """`ContactTolerances` scaled to one model: gap, step_gap [m]; rest_velocity, step_rest_velocity,
    velocity_scale [m/s]; stateless_step [s]; force_floor [N]."""

    gap: float
    step_gap: float
    rest_velocity: float
    step_rest_velocity: float
    stateless_step: float
    velocity_scale: float
    force_floor: float


#: what both schemes use unless told otherwise
DEFAULT_TOLERANCES = ContactTolerances()
