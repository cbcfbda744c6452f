"""Ctrl-C during a long solve: the solve stops at the engines' next checkpoint with
KeyboardInterrupt, and the interpreter stays usable (the next solve gives the command line's
result)."""
import os
import subprocess
import time

import pytest

import cli_cases
import hssbem
from conftest import COMM, assert_identical, datasets, options, problem, reference

pytestmark = pytest.mark.skipif(COMM.size > 1, reason="a call on several ranks is not interrupted (one rank leaving a collective step would leave the others waiting)")


def interrupted(call, delay=0.5):
    """call() with a SIGINT sent to this process `delay` seconds after it began, from another
    process (Ctrl-C at a terminal; a thread of this interpreter would wait for the interpreter's
    lock, which the call holds): whether it raised KeyboardInterrupt before its end (False: it
    ran to its end first)."""
    finished = []
    kill = subprocess.Popen(["/bin/sh", "-c", "sleep %g; kill -INT %d" % (delay, os.getpid())])
    start = time.perf_counter()
    try:
        with pytest.raises(KeyboardInterrupt):
            call()
            finished.append(time.perf_counter() - start)
            kill.wait()
            time.sleep(60)  # the signal came after the call's end: KeyboardInterrupt here
    finally:
        kill.wait()
    return not finished


def long_h2_solve():
    """sphere_l1 (998 vertices) under pressure on the H² operator at a tight tolerance: seconds
    of compression, factorization and GMRES, each a series of checkpoints (measured under load:
    9 s; the signal at 0.5 s stopped it after 1.1 s)."""
    p = cli_cases.example("sphere_pressure")
    return p, {"bem_mat_type": "h2", "ksp_rtol": 1e-12}


def test_ctrl_c_stops_a_solve_and_the_next_solve_works():
    p, o = long_h2_solve()
    assert interrupted(lambda: hssbem.solve(p, o)), "the solve ran to its end instead of stopping at the signal"
    # Usable afterwards: the call's options, error handler and progress hook were undone.
    r = hssbem.solve(problem("cube_dense"), options("cube_dense"))
    want = datasets(reference("cube_dense"), "fields")
    for name in ("displacement", "traction"):
        assert_identical(r.fields[name], want[name], name + " after the interrupted solve")
    assert r.attributes["mat_type"] == "dense"
    with pytest.raises(hssbem.Error) as e:  # errors are still one-line errors
        hssbem.solve(problem("cube_dense"), {"ksp_rtoll": 1})
    assert "ksp_rtoll" in str(e.value)
