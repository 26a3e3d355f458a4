"""Plots (matplotlib, Agg backend; optional dependency: pip install 'rocking-model[plot]').

- `plot_response`: rotation phi, top displacement (flexible oscillator), base slip (where the base slid),
  ground acceleration (and the vertical one, positive upward, with the uplift threshold it moves) and contact
  state (sliding shaded) over time, for one simulation (`response_figure`: the same as a matplotlib figure).
  An overturning is drawn as one: the curves of the motion stop at the overturning time (marked in every
  panel), the time after it is hatched "overturned" and the contact panel shows the level "overturned"
  (`contact_levels`), never a sliding or rocking state.
- `plot_overturning_spectrum`: Makris' overturning spectrum of a pulse grid, A / (g tan(alpha)) against
  omega_p / p, overturned or not.
"""
from __future__ import annotations

import math
from pathlib import Path
from typing import Sequence

import numpy as np

from .modes import OVERTURNED, SLIDING, Mode, stick_mode

CONTACT_LABELS = ["full", "left corner", "right corner", "flight", "overturned"]
#: the level of the contact panel of an overturned structure (after the modes' closed-corner levels 0-3)
OVERTURNED_LEVEL = 4


def contact_levels(codes) -> tuple:
    """The contact panel's data from the output ``contact`` (integer codes): (level of each sample: the closed
    corners of its mode, 0-3, sliding modes on their sticking mode, `OVERTURNED_LEVEL` once overturned;
    sliding mask; overturned mask)."""
    codes = np.asarray(codes, dtype=int)
    over = codes == OVERTURNED
    levels = np.array([OVERTURNED_LEVEL if c == OVERTURNED else int(stick_mode(Mode(c))) for c in codes], dtype=int)
    sliding = np.array([c != OVERTURNED and Mode(c) in SLIDING for c in codes], dtype=bool)
    return levels, sliding, over


def _pyplot():
    try:
        import matplotlib
    except ImportError:
        raise ImportError("plots need matplotlib: pip install 'rocking-model[plot]' (or matplotlib)") from None
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def response_figure(result, ground_motion, *, title: str = "", alpha: float | None = None, g: float = 9.81):
    """The figure of `plot_response` (matplotlib Figure; close it after use)."""
    plt = _pyplot()
    t = np.asarray(result.t)
    phi = np.asarray(result.phi)
    top = result.values.get("top_displacement") if hasattr(result, "values") else None
    # ag on a grid finer than the output so that short pulses show their shape
    tf = np.linspace(t[0], t[-1], max(2000, 4 * t.size))
    ag = np.array([ground_motion(float(x)) for x in tf])
    slip = np.asarray(result.values["slip"]) if hasattr(result, "values") and "slip" in result.values else None
    if slip is not None and not np.any(slip):
        slip = None                                   # the corners stuck throughout: no panel
    ratios = [3] + ([2] if top is not None else []) + ([1.5] if slip is not None else []) + [2, 1.3]
    fig, axes = plt.subplots(len(ratios), 1, figsize=(8.5, 2.2 * sum(ratios) / 2.0 + 1.2), sharex=True,
                             gridspec_kw={"height_ratios": ratios})
    imp = np.asarray(result.impact_times, dtype=float)
    over = np.asarray(result.overturned, dtype=bool)
    t_o = t[int(np.argmax(over))] if over.any() else None
    # the motion's curves stop at the overturning (the first overturned sample, the pose reached): after it
    # nothing is computed any more
    n_m = int(np.argmax(over)) + 1 if over.any() else t.size
    ax = axes[0]
    ax.plot(t[:n_m], phi[:n_m], color="C0", lw=1.2, label=r"$\varphi$")
    if alpha is not None:
        for s in (1, -1):
            ax.axhline(s * alpha, color="grey", ls="--", lw=0.8, label=r"$\pm\alpha$" if s == 1 else None)
    if imp.size:
        ax.plot(imp, np.interp(imp, t, phi), "x", color="C3", ms=5, label=f"impacts ({imp.size})")
    if t_o is not None:
        ax.axvline(t_o, color="C3", lw=1.0, label=f"overturned at {t_o:.3g} s")
        for a in axes[1:]:
            a.axvline(t_o, color="C3", lw=1.0)
        for a in axes:
            a.axvspan(t_o, t[-1], facecolor="none", edgecolor="0.6", hatch="//", lw=0,
                      label="overturned (no motion computed)" if a is ax else None)
    ax.set_ylabel(r"rotation $\varphi$ [rad]")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, borderaxespad=0.0)
    if title:
        ax.set_title(title, fontsize=10)
    panel = 1
    if top is not None:
        ax = axes[panel]
        ax.plot(t[:n_m], np.asarray(top)[:n_m], color="C4", lw=1.1, label="top mass")
        ax.set_ylabel("top displacement\n(rel. ground) [m]")
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, borderaxespad=0.0)
        panel += 1
    if slip is not None:
        ax = axes[panel]
        ax.plot(t[:n_m], slip[:n_m], color="C5", lw=1.1, label="base slip")
        ax.set_ylabel("slip [m]")
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, borderaxespad=0.0)
        panel += 1
    ax = axes[panel]
    ax.plot(tf, ag, color="C1", lw=1.0, label=r"$a_g$")
    vertical = getattr(ground_motion, "vertical", None)
    if vertical is not None:
        # the vertical ground acceleration (positive upward) moves the uplift threshold: (g + ag_v) tan(alpha)
        ag_v = np.array([vertical(float(x)) for x in tf])
        ax.plot(tf, ag_v, color="C9", lw=1.0, label=r"$a_{g,v}$ (vertical, up)")
        if alpha is not None:
            for s in (1, -1):
                ax.plot(tf, s * (g + ag_v) * math.tan(alpha), color="grey", ls=":", lw=0.8,
                        label=r"$\pm (g + a_{g,v})\,\tan\alpha$ (uplift)" if s == 1 else None)
        ax.set_ylabel("ground acc.\n" + r"$a_g$, $a_{g,v}$ [m/s$^2$]")
    elif alpha is not None:
        for s in (1, -1):
            ax.axhline(s * g * math.tan(alpha), color="grey", ls=":", lw=0.8,
                       label=r"$\pm g\,\tan\alpha$ (uplift)" if s == 1 else None)
    if vertical is None:
        ax.set_ylabel(r"ground acc. $a_g$ [m/s$^2$]")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, borderaxespad=0.0)
    ax = axes[panel + 1]
    # the closed corners of each mode (sliding modes drawn on their sticking mode, shaded) up to the
    # overturning, then the level "overturned" in its own colour
    levels, sliding, over_c = contact_levels(result.contact)
    ax.step(t[:n_m], levels[:n_m], where="post", color="C2")
    if over_c.any():
        k = int(np.argmax(over_c))
        ax.step(t[k:], levels[k:], where="post", color="C3", lw=2.0, label="overturned")
    if sliding.any():
        ax.fill_between(t, -0.5, OVERTURNED_LEVEL + 0.5, where=sliding, step="post", color="C1", alpha=0.25,
                        lw=0, label="sliding")
    if sliding.any() or over_c.any():
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, borderaxespad=0.0)
    n_levels = OVERTURNED_LEVEL + 1 if over_c.any() else OVERTURNED_LEVEL
    ax.set_yticks(range(n_levels), CONTACT_LABELS[:n_levels])
    ax.set_ylim(-0.5, n_levels - 0.5)
    ax.set_ylabel("contact")
    ax.set_xlabel("time t [s]")
    for a in axes:
        a.grid(alpha=0.3)
    fig.tight_layout()
    return fig


def plot_response(result, ground_motion, path, *, title: str = "", alpha: float | None = None,
                  g: float = 9.81) -> Path:
    """Write a PNG with panels sharing the time axis: rotation phi [rad] (with +-alpha, impacts and the
    overturning time), the top displacement [m] when the result has one (flexible oscillator), ground
    acceleration ag [m/s2] (with +-g tan(alpha), the uplift threshold of the rigid block) and the contact
    state; legends sit right of the panels, clear of the curves. ``result`` is a `Result`;
    ``ground_motion`` a callable ag(t) [m/s2] (one with a ``vertical`` component ag_v(t) has it drawn with ag,
    and the uplift threshold (g + ag_v) tan(alpha)); ``alpha`` [rad] the slenderness (None: not drawn);
    g [m/s2]."""
    plt = _pyplot()
    fig = response_figure(result, ground_motion, title=title, alpha=alpha, g=g)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120, bbox_inches="tight")
    plt.close(fig)
    return path


def plot_overturning_spectrum(rows: Sequence[dict], path, *, title: str = "") -> Path:
    """Write Makris' overturning spectrum of a pulse grid: each case a marker at (omega_p / p,
    A / (g tan(alpha))), red if it overturned, else coloured by max|phi|/alpha; the uplift line A = g tan(alpha).
    ``rows`` are ensemble rows (`rocking_model.ensemble.run_case`) with w_ratio, a_ratio, overturned."""
    plt = _pyplot()
    rows = [r for r in rows if not r.get("error") and np.isfinite(r.get("w_ratio", np.nan))]
    if not rows:
        raise ValueError("no rows with a frequency ratio omega_p/p: the spectrum needs a rigid-block pulse grid")
    w = np.array([r["w_ratio"] for r in rows])
    a = np.array([r["a_ratio"] for r in rows])
    over = np.array([bool(r["overturned"]) for r in rows])
    phi = np.array([r["max_phi_over_alpha"] for r in rows])
    fig, ax = plt.subplots(figsize=(7.5, 5.5))
    sc = ax.scatter(w[~over], a[~over], c=np.clip(phi[~over], 0, 1), cmap="Blues", vmin=0, vmax=1, s=22,
                    marker="o", edgecolors="k", linewidths=0.3, label="no overturning")
    ax.scatter(w[over], a[over], color="C3", s=26, marker="s", label="overturned")
    ax.axhline(1.0, color="grey", ls="--", lw=0.8)
    ax.text(w.min(), 1.0, r" uplift: $A = g\tan\alpha$", va="bottom", color="grey", fontsize=8)
    cb = fig.colorbar(sc, ax=ax)
    cb.set_label(r"max $|\varphi| / \alpha$ (not overturned)")
    ax.set_xlabel(r"frequency ratio $\omega_p / p$ [1]")
    ax.set_ylabel(r"amplitude ratio $A / (g \tan\alpha)$ [1]")
    ax.set_title(title or "Overturning spectrum", fontsize=10, pad=22)
    ax.legend(loc="lower left", bbox_to_anchor=(0.0, 1.0), ncol=2, fontsize=8, frameon=False)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path
