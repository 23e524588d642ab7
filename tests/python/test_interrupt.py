"""Ctrl-C: a real SIGINT during a long polygonization ends it with KeyboardInterrupt within a
moment (for the run's length SIGINT cancels the run's cdp.CancelToken, which every phase polls),
and the module works as before afterwards, Python's own handler back in place. A token cancelled
from another thread ends a run with cdp.CancelledError."""
import os
import signal
import threading
import time

import numpy as np
import pytest

import cdp

# Each run below takes several seconds uninterrupted (measured: the adaptive torus at factor 60,
# 1.2 million triangles, 6 s; Marching Cubes of the sphere at cell 0.003, 4.2 million, 8 s;
# Marching Tetrahedra at cell 0.005, about 7 s), so an interrupt seen only when the run ends
# fails the 2 s bound; the signal comes at 0.3 s.
DELAY = 0.3


@pytest.fixture(autouse=True)
def python_sigint_handler():
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, previous)


@pytest.fixture(scope="module")
def reference():
    sphere = cdp.sphere(radius=1)
    return sphere, cdp.polygonize(sphere, factor=2)


def interrupted_after(run):
    """Seconds from the signal to the KeyboardInterrupt."""
    sent = []

    def send():
        sent.append(time.monotonic())
        os.kill(os.getpid(), signal.SIGINT)

    timer = threading.Timer(DELAY, send)
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            run()
    finally:
        timer.cancel()
    assert sent, "the run ended before the signal was sent"
    return time.monotonic() - sent[0]


def still_works(reference):
    sphere, (V, F, _, stats) = reference
    V2, F2, _, stats2 = cdp.polygonize(sphere, factor=2)
    assert np.array_equal(V, V2) and np.array_equal(F, F2)


@pytest.mark.parametrize("run", [
    lambda: cdp.polygonize(cdp.torus(major_radius=1, minor_radius=0.3), factor=60, min_edge=1e-4),
    lambda: cdp.marching_cubes(cdp.sphere(radius=1), cell=0.003),
    lambda: cdp.marching_tetrahedra(cdp.sphere(radius=1), cell=0.005),
], ids=["adaptive", "mc", "mt"])
def test_sigint_interrupts_a_long_run(reference, run):
    assert interrupted_after(run) < 2.0
    still_works(reference)


def test_sigint_interrupts_a_callable_field(reference):
    def torus(p):
        return (np.sqrt(p[:, 0] ** 2 + p[:, 1] ** 2) - 1) ** 2 + p[:, 2] ** 2 - 0.09

    field = cdp.callable_field(torus, ((-1.5, -1.5, -0.5), (1.5, 1.5, 0.5)), trace=False)
    assert interrupted_after(lambda: cdp.polygonize(field, factor=20)) < 2.0
    still_works(reference)


def test_keyboard_interrupt_raised_by_the_function(reference):
    calls = [0]

    def torus(p):
        calls[0] += 1
        if calls[0] == 200:
            raise KeyboardInterrupt
        return (np.sqrt(p[:, 0] ** 2 + p[:, 1] ** 2) - 1) ** 2 + p[:, 2] ** 2 - 0.09

    field = cdp.callable_field(torus, ((-1.5, -1.5, -0.5), (1.5, 1.5, 0.5)), trace=False)
    with pytest.raises(KeyboardInterrupt):
        cdp.polygonize(field, factor=3)
    still_works(reference)
    V, F, _, _ = cdp.polygonize(field, factor=3)  # the field itself is fine too
    assert len(F) > 0


def test_sigint_after_a_run_is_pythons_again(reference):
    still_works(reference)
    with pytest.raises(KeyboardInterrupt):
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(2)


@pytest.mark.parametrize("run", [
    lambda token: cdp.polygonize(cdp.torus(major_radius=1, minor_radius=0.3), factor=60, min_edge=1e-4, cancel=token),
    lambda token: cdp.marching_cubes(cdp.sphere(radius=1), cell=0.003, cancel=token),
], ids=["adaptive", "mc"])
def test_a_token_cancelled_from_another_thread_ends_the_run(reference, run):
    token = cdp.CancelToken()
    assert not token.cancelled
    timer = threading.Timer(DELAY, token.cancel)
    start = time.monotonic()
    timer.start()
    try:
        with pytest.raises(cdp.CancelledError, match="cancelled"):
            run(token)
    finally:
        timer.cancel()
    assert token.cancelled
    assert time.monotonic() - start < DELAY + 2.0
    still_works(reference)
    token.reset()
    V, F, _, _ = cdp.polygonize(cdp.sphere(radius=1), factor=2, cancel=token)  # a reset token lets a run finish
    assert len(F) > 0
