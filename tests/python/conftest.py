"""The Python suites' harness: the module from the build tree (PYTHONPATH), the command line's
results (cli_cases.py) and a directory every rank shares."""
import os
import sys

import h5py
import numpy as np
import pytest
from mpi4py import MPI

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import cli_cases  # noqa: E402
import hssbem  # noqa: E402,F401  (initialises PETSc through petsc4py)

COMM = MPI.COMM_WORLD


@pytest.fixture
def comm():
    return COMM


@pytest.fixture
def shared_tmp(tmp_path):
    """A directory all ranks see (rank 0's tmp_path)."""
    return COMM.bcast(str(tmp_path), root=0)


def reference(case):
    """The command line's result file of `case` at this run's number of ranks: from the ctest
    fixture (HSSBEM_PY_REFERENCES), or made here on one rank (HSSBEM_DRIVER)."""
    out = os.environ.get("HSSBEM_PY_REFERENCES", "")
    path = os.path.join(out, "%s_np%d.h5" % (case, COMM.size))
    if out and os.path.exists(path):
        return path
    if COMM.size > 1 or not os.environ.get("HSSBEM_DRIVER"):
        pytest.skip("no command-line result for %s at %d ranks (run cli_cases.py, or set HSSBEM_DRIVER)" % (case, COMM.size))
    return cli_cases.run_case(case, out or os.path.join(os.getcwd(), "python_references"), os.environ["HSSBEM_DRIVER"])


def problem(case):
    """The case's problem as a dict (what the command line solved)."""
    return cli_cases.CASES[case][0]()


def options(case):
    """The case's command-line options as a dict for hssbem (without the dashes)."""
    o = cli_cases.CASES[case][1]
    return {o[i][1:]: o[i + 1] for i in range(0, len(o), 2)}


def datasets(path, group):
    """Every dataset under `group` of a result file, by its path below the group."""
    out = {}
    with h5py.File(path, "r") as f:
        if group not in f:
            return out
        f[group].visititems(lambda name, obj: out.__setitem__(name, obj[()]) if isinstance(obj, h5py.Dataset) else None)
    return out


def attributes(path, group="/"):
    with h5py.File(path, "r") as f:
        return dict(f[group].attrs)


def assert_identical(a, b, what):
    a, b = np.asarray(a), np.asarray(b)
    assert a.shape == b.shape, "%s: shapes %s and %s" % (what, a.shape, b.shape)
    assert np.array_equal(a, b, equal_nan=a.dtype.kind == "f"), "%s differs: largest difference %g" % (what, np.nanmax(np.abs(a - b)))
