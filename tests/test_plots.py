"""Plots of the command line: every label in a legend beside the panels (no text drawn over the
curves), the flexible oscillator's top displacement in its own panel."""
from __future__ import annotations

import numpy as np
import pytest

from rocking_model import FlexibleOscillator, RigidBlock, SinePulse, simulate

pytest.importorskip("matplotlib")
from rocking_model.plotting import response_figure  # noqa: E402


def _labels(ax):
    legend = ax.get_legend()
    return [t.get_text() for t in legend.get_texts()] if legend is not None else []


def test_rigid_response_plot_labels_sit_in_legends():
    block = RigidBlock(b=0.2, h=1.0)
    motion = SinePulse(4.5, 4.0 * 3.141592653589793)
    res = simulate(block, motion, 4.0, on_report="ignore")
    fig = response_figure(res, motion, alpha=block.alpha, g=block.g)
    try:
        axes = fig.axes
        # a slip panel only where the base slid: here the pivot slides for a moment at the lift-off of the
        # overturning fall (the zero of its force, where neither sticking nor flight is consistent)
        slid = bool(np.any(np.asarray(res.values["slip"])))
        assert len(axes) == 3 + slid
        axes = [ax for ax in axes if ax.get_ylabel() != "slip [m]"]
        assert all(not ax.texts for ax in axes), [t.get_text() for ax in axes for t in ax.texts]
        assert any("tan" in s and "uplift" in s for s in _labels(axes[1]))
        assert any(s.startswith("overturned at") for s in _labels(axes[0]))
        assert any(s.startswith("impacts (") for s in _labels(axes[0]))
        # the legends are outside the axes (to their right): they cannot cover a curve
        fig.canvas.draw()
        for ax in axes:
            legend = ax.get_legend()
            if legend is not None:
                assert legend.get_window_extent().x0 >= ax.get_window_extent().x1
    finally:
        import matplotlib.pyplot as plt
        plt.close(fig)


def test_flexible_response_plot_has_the_top_displacement():
    model = FlexibleOscillator()
    motion = SinePulse(3.0, 3.0 * 3.141592653589793)
    res = simulate(model, motion, 2.0, on_report="ignore")
    fig = response_figure(res, motion)
    try:
        labels = [ax.get_ylabel() for ax in fig.axes]
        # (it bounces and lands 0.08 mm off its rest position: the slip panel shows that)
        assert np.max(np.abs(res.slip)) > 1e-5
        assert len(fig.axes) == 5 and "top displacement" in labels[1] and "slip" in labels[2]
        (line,) = fig.axes[1].get_lines()
        assert list(line.get_ydata()) == list(res.top_displacement)
    finally:
        import matplotlib.pyplot as plt
        plt.close(fig)


def test_an_overturn_is_plotted_as_an_overturn():
    """After overturning the plot drew the frozen last mode (a sliding one) for the rest of the run.
    Now the contact data after the overturning time are the level "overturned", never sliding; the curves of
    the motion stop at the overturning time, which every panel marks."""
    import math

    from rocking_model.modes import OVERTURNED
    from rocking_model.plotting import CONTACT_LABELS, OVERTURNED_LEVEL, contact_levels

    block = RigidBlock(b=0.2, h=1.0, mu=0.5)          # its pivot slides in the final fall
    motion = SinePulse(4.5, 4.0 * math.pi)
    res = simulate(block, motion, 8.0, on_report="ignore")
    over = np.asarray(res.overturned, dtype=bool)
    k = int(np.argmax(over))
    t_o = res.t[k]
    assert over[-1] and 2.5 < t_o < 3.5
    levels, sliding, over_c = contact_levels(res.contact)
    assert np.array_equal(over_c, over) and np.all(res.contact[k:] == OVERTURNED)
    assert np.all(levels[k:] == OVERTURNED_LEVEL) and CONTACT_LABELS[OVERTURNED_LEVEL] == "overturned"
    assert sliding[:k].any() and not sliding[k:].any()      # slid before, never after
    fig = response_figure(res, motion, alpha=block.alpha, g=block.g)
    try:
        axes = fig.axes
        phi_line = axes[0].get_lines()[0]
        assert phi_line.get_xdata()[-1] == t_o                      # the motion's curve stops there
        contact_ax = axes[-1]
        lines = contact_ax.get_lines()
        motion_line = next(ln for ln in lines if ln.get_color() == "C2")
        over_line = next(ln for ln in lines if ln.get_label() == "overturned")
        assert motion_line.get_xdata()[-1] == t_o
        assert set(over_line.get_ydata()) == {OVERTURNED_LEVEL} and over_line.get_xdata()[0] == t_o
        assert [t.get_text() for t in contact_ax.get_yticklabels()][-1] == "overturned"
        assert "overturned" in _labels(contact_ax) and "sliding" in _labels(contact_ax)
        for ax in axes:                                             # the overturning time marked everywhere
            assert any(list(ln.get_xdata()) == [t_o, t_o] for ln in ax.get_lines()), ax.get_ylabel()
    finally:
        import matplotlib.pyplot as plt
        plt.close(fig)
