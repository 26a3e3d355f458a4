"""Plots of the command line (issue 14): every label in a legend beside the panels (no text drawn over the
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
        assert len(axes) == 3
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
