#!/usr/bin/env python3
"""Solve a problem file from Python and check it against its closed form.

    PYTHONPATH=build/python python3 examples/python/solve.py [problem.json] [option value ...]
    PYTHONPATH=build/python mpirun -n 2 python3 examples/python/solve.py

The default problem is the shipped default example, a unit sphere under uniform pressure p = 100
(E = 1000, nu = 0.3), whose exact displacement is u = -p (1 - 2 nu) / E x = -0.04 x. Options
follow as the command line spells them (-bem_mat_type h2 -ksp_rtol 1e-10). Prints what the
command line prints about the solve, the largest error against the closed form (the default
problem), and writes sphere_python.h5 (the same file as `hssbem -problem ... -o`).
"""
import os
import sys

import numpy as np

import hssbem
from mpi4py import MPI

here = os.path.dirname(os.path.abspath(__file__))
default = os.path.join(here, "..", "..", "meshes", "examples", "sphere_pressure.json")
given = len(sys.argv) > 1 and not sys.argv[1].startswith("-")
problem = sys.argv[1] if given else default
options = sys.argv[2:] if given else sys.argv[1:]

comm = MPI.COMM_WORLD
try:
    result = hssbem.solve(problem, options + ["-o", "sphere_python.h5"], comm=comm)
except hssbem.Error as e:
    if comm.rank == 0:
        print("solve.py: error: %s" % e, file=sys.stderr)
    sys.exit(1)

if comm.rank == 0:
    print("hssbem imported from %s" % os.path.dirname(os.path.dirname(os.path.abspath(hssbem.__file__))))
    a = result.attributes
    print("solved with %s/%s on %d ranks: %d iterations, relative residual %.3e" % (a["ksp_type"], a["pc_type"], a["ranks"], result.iterations, a["residual"]))
    u = result.fields["displacement"]
    print("largest displacement %.6f at %d vertices; wrote sphere_python.h5" % (np.abs(u).max(), len(u)))
    if problem == default:
        exact = -0.04 * result.mesh["vertices"]
        print("largest error against the closed form u = -0.04 x: %.2e (of 0.04)" % np.abs(u - exact).max())
