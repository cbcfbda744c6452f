#!/usr/bin/python3
"""Failures on one rank of the distributed H² factorization end cleanly, whatever fails where.

Usage:
    test_rank_faults.py --driver PATH/hssbem --shim PATH/libhssbem_fail_new.so
                        --meshes REPO/meshes --mpiexec mpiexec [--sweep-max N]
                        [unittest arguments]

Every case runs the driver on a small mixed problem (sphere_l0: 251 nodes, 753 unknowns; H²
leaves of 16 nodes and no dense-top shortcut, so PC h2 has levels below its top on every rank
count) with a fault on one rank only, and asserts the one error path: exit status 1, exactly one
"hssbem: error:" line, no PETSc traceback, no abort, no result or temporary file, within a
time-out (a rank left waiting in a collective call is a hang, and fails the case).

  * FaultSiteTests: the sites where a rank fails alone before the others' collective calls:
    Partition (the METIS partition's step), Exchange (the allocation of what arrives in an
    exchange of records), SpreadTopBreakdown (a spread top's trial solve judged failed on that
    rank only: every rank must agree on the breakdown, which stops GMRES with DIVERGED_PC_FAILED).
  * DriverOptionTests: -hssbem_error_timeout (positive and finite) and -hssbem_residual_max (a
    preonly solve with a loose PC is no solution: an error, nothing written).
  * AllocationSweepTests: the Nth large allocation (operator new of 64 KiB or more) on one rank
    fails during PC h2 set-up (the driver preloads the test shim tests/mpi/fail_new.cpp, armed
    by -hssbem_fault PCSetUp -hssbem_fault_kind alloc -hssbem_fault_count N). A first run counts
    the set-up's large allocations on that rank (T: 179 at 2 ranks, 221 at 3); then every N
    from 1 to T runs when T is at most --sweep-max, else --sweep-max values of N spread evenly
    over 1..T, first and last included (CI: 12 each; by hand, --sweep-max 1000 runs them all). At 2 ranks with the top spread over the ranks (ScaLAPACK), at 3 ranks with the
    top on rank 0 (parts' roots on two levels of the tree).
"""

import argparse
import glob
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import unittest

DRIVER = SHIM = MESHES = MPIEXEC = None
SWEEP_MAX = 12
TIMEOUT = 60  # one run takes about 2 s; a hang is a failure, not a wait
MIN_BYTES = 65536  # the shim's "large": 179 such allocations at 2 ranks, 221 at 3 (5 043 of 4 KiB or more)

ENV = dict(os.environ)
ENV.update(OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1", OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")

# The problem's solver: the H² matrix, GMRES + PC h2 with its levels (no dense-top shortcut).
SOLVER = ["-bem_mat_type", "h2", "-mat_h2_leaf_size", "16", "-pc_type", "h2", "-pc_h2_top_size", "0",
          "-pc_h2_top_when_cheaper", "0", "-hssbem_error_timeout", "10", "-options_left"]
SPREAD = ["-pc_h2_single_top_from", "1"]   # a single-precision top: spread over the ranks
ON_RANK0 = ["-pc_h2_spread_top", "0"]


class Run:
    def __init__(self, cmd, proc, tmp):
        self.cmd, self.returncode = cmd, proc.returncode
        self.output = proc.stdout_text + "\n" + proc.stderr_text
        self.tmp = tmp

    def describe(self):
        return "command: %s\nexit status: %s\n--- output ---\n%s" % (" ".join(self.cmd), self.returncode, self.output.strip())


class FaultCase(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="hssbem-faults-")
        shutil.copy(os.path.join(MESHES, "sphere_l0.msh"), self.tmp)
        spec = {"mesh": "sphere_l0.msh", "material": {"E": 1000.0, "nu": 0.3},
                "boundary": [{"where": {"region": "south"}, "displacement": [0, 0, 0]},
                             {"where": {"region": "north"}, "traction": [0, 0, 20.0]}]}
        with open(os.path.join(self.tmp, "problem.json"), "w") as f:
            json.dump(spec, f)

    def tearDown(self):
        shutil.rmtree(self.tmp, ignore_errors=True)

    def run_driver(self, np, *args, env=None):
        cmd = [MPIEXEC, "-n", str(np), "--oversubscribe", DRIVER, "-problem", "problem.json",
               "-o", os.path.join(self.tmp, "out.h5")] + [str(a) for a in args]
        # A session of its own, so that a hang is ended with every rank of it.
        proc = subprocess.Popen(cmd, cwd=self.tmp, env=env or ENV, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                universal_newlines=True, errors="replace", start_new_session=True)
        try:
            proc.stdout_text, proc.stderr_text = proc.communicate(timeout=TIMEOUT)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.communicate()
            self.fail("hang: no end within %d s\ncommand: %s" % (TIMEOUT, " ".join(cmd)))
        return Run(cmd, proc, self.tmp)

    def leftovers(self):
        return sorted(n for n in os.listdir(self.tmp) if n.endswith((".h5", ".xdmf")) or ".tmp." in n)

    def assertOneCleanError(self, r, pattern):
        self.assertEqual(r.returncode, 1, r.describe())
        self.assertEqual(len(re.findall(r"hssbem: error: ", r.output)), 1, "expected exactly one error line\n" + r.describe())
        self.assertRegex(r.output, re.compile(pattern, re.DOTALL), r.describe())
        self.assertNotRegex(r.output, r"PETSC ERROR|Caught signal|MPI_ABORT|MPI_Abort|terminate called", r.describe())
        self.assertRegex(r.output, r"There are no unused options|There are options you set", "PetscFinalize did not run\n" + r.describe())
        self.assertEqual(self.leftovers(), [], "a result or temporary file was left\n" + r.describe())


class FaultSiteTests(FaultCase):
    def test_partition_on_one_rank(self):
        for kind, pattern in (("error", r"injected fault at Partition \(on rank 1\)"), ("oom", r"out of memory \(on rank 1\)")):
            with self.subTest(kind=kind):
                r = self.run_driver(2, *SOLVER, "-hssbem_fault", "Partition", "-hssbem_fault_kind", kind, "-hssbem_fault_rank", "1")
                self.assertOneCleanError(r, r"partition of the surface failed: " + pattern)

    def test_exchange_allocation_on_one_rank(self):
        # The first exchange of records on rank 2 of 3: the factorization's leaves' cross blocks.
        r = self.run_driver(3, *SOLVER, "-hssbem_fault", "Exchange", "-hssbem_fault_kind", "oom", "-hssbem_fault_rank", "2")
        self.assertOneCleanError(r, r"PC h2 set-up: out of memory \(on rank 2\)")

    def test_spread_top_breakdown_on_one_rank(self):
        r = self.run_driver(2, *SOLVER, *SPREAD, "-hssbem_fault", "SpreadTopBreakdown", "-hssbem_fault_rank", "1")
        self.assertOneCleanError(r, r"DIVERGED_PC_FAILED")


class DriverOptionTests(FaultCase):
    """The options that decide how the error path itself behaves are checked before it runs."""

    def test_error_timeout_must_be_positive_and_finite(self):
        # nan and inf would wait forever for a rank stuck in a collective call; 0 and -1 aborted
        # a successful run.
        for value in ("nan", "inf", "0", "-1"):
            with self.subTest(value=value):
                r = self.run_driver(2, "-hssbem_error_timeout", value, "-options_left")
                self.assertOneCleanError(r, r"-hssbem_error_timeout must lie in \(0, 86400\], got " + value)

    def test_loose_preonly_is_no_solution(self):
        # KSP reports preonly as converged whatever the PC: the true residual decides (Jacobi
        # alone leaves about 7 here), and nothing is written.
        r = self.run_driver(2, "-bem_mat_type", "dense", "-ksp_type", "preonly", "-pc_type", "jacobi", "-options_left")
        self.assertOneCleanError(r, r"the linear solve gave no solution: its true relative residual .* above -hssbem_residual_max 0\.0001")
        r = self.run_driver(1, "-hssbem_residual_max", "nan", "-options_left")
        self.assertOneCleanError(r, r"-hssbem_residual_max must be > 0, got nan")


class AllocationSweepTests(FaultCase):
    def sweep(self, np, rank, extra):
        report = os.path.join(self.tmp, "count.txt")
        env = dict(ENV, LD_PRELOAD=SHIM, HSSBEM_FAIL_NEW_REPORT=report, HSSBEM_FAIL_NEW_MIN_BYTES=str(MIN_BYTES))
        fault = ["-hssbem_fault", "PCSetUp", "-hssbem_fault_kind", "alloc", "-hssbem_fault_rank", str(rank)]
        r = self.run_driver(np, *SOLVER, *extra, *fault, "-hssbem_fault_count", "0", env=env)
        self.assertEqual(r.returncode, 0, "the counting run failed\n" + r.describe())
        with open(report) as f:
            total = int(f.read().split()[0])
        os.remove(report)
        for name in glob.glob(os.path.join(self.tmp, "out.*")):
            os.remove(name)
        self.assertGreater(total, 10, "too few large allocations counted: is the shim armed?")
        runs = list(range(1, total + 1))
        if total > SWEEP_MAX:
            runs = sorted({1 + round(i * (total - 1) / (SWEEP_MAX - 1)) for i in range(SWEEP_MAX)})
        sys.stderr.write("\n  %d ranks, rank %d: %d large allocations in PC h2 set-up; failing N = %s\n" % (np, rank, total, runs if len(runs) < 12 else "%d values in 1..%d" % (len(runs), total)))
        for n in runs:
            with self.subTest(ranks=np, rank=rank, n=n):
                r = self.run_driver(np, *SOLVER, *extra, *fault, "-hssbem_fault_count", n, env=env)
                self.assertOneCleanError(r, r"out of memory \(on rank %d\)" % rank)

    def test_two_ranks_spread_top(self):
        self.sweep(2, 1, SPREAD)

    def test_three_ranks_top_on_rank_0(self):
        self.sweep(3, 2, ON_RANK0)


def main():
    global DRIVER, SHIM, MESHES, MPIEXEC, SWEEP_MAX
    parser = argparse.ArgumentParser(add_help=False)
    parser.add_argument("--driver", required=True)
    parser.add_argument("--shim", required=True)
    parser.add_argument("--meshes", required=True)
    parser.add_argument("--mpiexec", required=True)
    parser.add_argument("--sweep-max", type=int, default=SWEEP_MAX)
    args, rest = parser.parse_known_args()
    DRIVER, SHIM, MESHES = os.path.abspath(args.driver), os.path.abspath(args.shim), os.path.abspath(args.meshes)
    MPIEXEC, SWEEP_MAX = args.mpiexec, args.sweep_max
    unittest.main(argv=[sys.argv[0]] + rest)


if __name__ == "__main__":
    main()
