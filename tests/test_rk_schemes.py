"""The generated Runge-Kutta steppers (issue 14): each step and its dense output equal scipy's DOP853 / RK45
(the same tableaux and error control, on Python floats instead of numpy), and the generated source is
registered with linecache so that tracebacks show it."""
from __future__ import annotations

import math
import traceback

import numpy as np
import pytest
from scipy.integrate import DOP853 as ScipyDOP853
from scipy.integrate import RK45 as ScipyRK45

from rocking_model.integrators.dop853 import DOP853
from rocking_model.integrators.dopri5 import DOPRI5


def forced_pendulum(t, y):
    """A damped pendulum under a harmonic force: smooth, non-linear, with a non-trivial step sequence."""
    return [y[1], -math.sin(y[0]) - 0.1 * y[1] + 0.5 * math.cos(1.3 * t)]


@pytest.mark.parametrize("ours, theirs", [(DOP853, ScipyDOP853), (DOPRI5, ScipyRK45)], ids=["DOP853", "DOPRI5"])
@pytest.mark.parametrize("rtol", [1e-5, 1e-10])
def test_steps_and_dense_output_equal_scipy(ours, theirs, rtol):
    y0, atol = [1.0, 0.0], [1e-3 * rtol, 1e-3 * rtol]
    a = ours(forced_pendulum, 0.0, y0, rtol, atol, first_step=0.01)
    b = theirs(lambda t, y: np.array(forced_pendulum(t, list(y))), 0.0, np.array(y0), t_bound=1e9,
               rtol=rtol, atol=np.array(atol), first_step=0.01)
    n_checked = 0
    while a.t < 8.0:
        # scipy starts each step where ours did, with the step size ours took (its controller then proposes
        # the next one from the same error estimate)
        b.t, b.y, b.f = a.t, np.array(a.y), np.array(a.f)
        rejected = a.n_rejected
        a.step(1e9)
        rejected = a.n_rejected > rejected
        h = a.t - a.t_old
        b.h_abs, b.t_old = h, None
        b.step()
        assert b.status == "running"
        assert b.t == pytest.approx(a.t, rel=1e-15, abs=1e-15)
        np.testing.assert_allclose(a.y, b.y, rtol=1e-13, atol=1e-15)
        # the proposed next step: the error estimate is a difference of O(1) stage sums that is 1e-8 to 1e-12
        # of them, summed in another order than scipy's, so it agrees to some 1e-6 (a wrong exponent, safety
        # factor or norm would be off by a percent or more)
        # after a rejection within the step the step may not grow (scipy's rule too, which it does not know
        # about here: it was handed the accepted size)
        assert a.h_abs == pytest.approx(min(h, b.h_abs) if rejected else b.h_abs, rel=1e-4)
        da, db = a.dense_output(), b.dense_output()
        for x in np.linspace(a.t_old, a.t, 7):
            np.testing.assert_allclose(da(float(x)), db(x), rtol=1e-12, atol=1e-14)
        n_checked += 1
    assert n_checked > 10


def test_generated_code_shows_in_tracebacks():
    """An exception inside a generated step names the generated file and shows its source line."""
    calls = []

    def fails_on_third_stage(t, y):
        calls.append(t)
        if len(calls) == 3:
            raise ZeroDivisionError("boom")
        return forced_pendulum(t, y)

    stepper = DOP853(fails_on_third_stage, 0.0, [1.0, 0.0], 1e-8, [1e-10, 1e-10], first_step=0.01)
    with pytest.raises(ZeroDivisionError) as info:
        stepper.step(1.0)
    text = "".join(traceback.format_exception(info.value))
    assert "<rocking_model generated DOP853 n=2>" in text
    assert "= fun(t + " in text          # the generated line itself, read from linecache


def test_failed_step_is_flagged():
    """A step accepted only because no smaller step exists (error above tolerance) is flagged, not passed."""
    # y' = 1/(t - 0.5): the error cannot be met near the singularity
    stepper = DOPRI5(lambda t, y: [1.0 / (t - 0.5) if t != 0.5 else 1e300], 0.0, [0.0], 1e-12, [1e-14],
                     first_step=1e-3)
    while not stepper.failed and stepper.t < 0.5:
        stepper.step(0.5)
    assert stepper.failed
    assert "accepted at the smallest step size" in stepper.failure


def test_dop853_takes_an_underflowing_error_estimate_as_zero():
    """A state near 1e-155 of its scale: e5 is 0.0 and 0.01 e3 underflows, so Hairer's norm is 0 / 0. The step's
    error is zero (as scipy's DOP853 and the C engine take it), not a ZeroDivisionError: the run reaches t_bound
    with every step accepted and the state still of that size."""
    stepper = DOP853(lambda t, y: [math.sin(y[0]) - 0.5 * y[0]], 0.0, [6.702559824942551e-155], 0.01, [0.01])
    while stepper.t < 1.5:
        stepper.step(1.5)
    assert stepper.t == 1.5 and stepper.n_rejected == 0 and not stepper.failed
    assert 0.0 < stepper.y[0] < 1e-150
