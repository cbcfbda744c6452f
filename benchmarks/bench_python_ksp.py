#!/usr/bin/python3
"""A petsc4py KSP on hssbem's operator with PC h2 against the command line, on the same static
problem: iterations, residual, wall and CPU time, the two alternating in fresh processes.

    /usr/bin/python3 scripts/gen_meshes.py --disk-triangles 20000 --out organ20k.msh
    OMP_NUM_THREADS=2 OPENBLAS_NUM_THREADS=2 PYTHONPATH=build/python /usr/bin/python3 \\
        benchmarks/bench_python_ksp.py --driver build/bin/hssbem --mesh organ20k.msh --rounds 1

The problem: the organ's region "bottom" clamped, its region "top" loaded by a traction
(0, 0, -50), E = 3000, nu = 0.45; -bem_mat_type h2 with every other option at its default. The
command line solves it with its KSP (GMRES, PC h2); the Python side builds A and b with
hssbem.operator and solves with a KSP of its own set up as docs/python.md shows (GMRES, the
command line's restart and rtol, right preconditioning, PC h2), then checks ||b - A x|| / ||b||.
"""
import argparse
import json
import os
import resource
import subprocess
import sys
import time

import h5py


def problem(mesh, out_dir):
    spec = {"mesh": os.path.abspath(mesh), "material": {"E": 3000, "nu": 0.45},
            "boundary": [{"where": {"region": "bottom"}, "displacement": [0, 0, 0]},
                         {"where": {"region": "top"}, "traction": [0, 0, -50]}]}
    path = os.path.join(out_dir, "static.json")
    with open(path, "w") as f:
        json.dump(spec, f, indent=1)
    return path


def python_side(prob):
    from petsc4py import PETSc
    import hssbem
    w, c = time.perf_counter(), time.process_time()
    A, b = hssbem.operator(prob, {"bem_mat_type": "h2"})
    built = time.perf_counter() - w
    ksp = PETSc.KSP().create(A.getComm())
    ksp.setOperators(A)
    ksp.setType("gmres")
    ksp.setGMRESRestart(hssbem.option_default("ksp_gmres_restart"))
    ksp.setTolerances(rtol=hssbem.option_default("ksp_rtol"))
    ksp.setPCSide(PETSc.PC.Side.RIGHT)
    ksp.getPC().setType("h2")
    ksp.setFromOptions()
    x = b.duplicate()
    s = time.perf_counter()
    ksp.solve(b, x)
    solved = time.perf_counter() - s
    r = b.duplicate()
    A.mult(x, r)
    r.aypx(-1.0, b)
    print("python iterations %d residual %.3e reason %d operator_s %.2f solve_s %.2f wall_s %.2f cpu_s %.2f" %
          (ksp.getIterationNumber(), r.norm() / b.norm(), ksp.getConvergedReason(), built, solved, time.perf_counter() - w, time.process_time() - c))
    return 0


def timed(command):
    """(wall s, CPU s of the children, stdout)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    w = time.perf_counter()
    p = subprocess.run(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, universal_newlines=True)
    wall = time.perf_counter() - w
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if p.returncode != 0:
        sys.exit("failed: %s\n%s\n%s" % (" ".join(command), p.stdout, p.stderr))
    return wall, after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime, p.stdout


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--driver")
    ap.add_argument("--mesh")
    ap.add_argument("--rounds", type=int, default=1)
    ap.add_argument("--dir", default="bench_python_ksp")
    ap.add_argument("--python-side", metavar="PROBLEM", help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.python_side:
        return python_side(a.python_side)
    os.makedirs(a.dir, exist_ok=True)
    prob = problem(a.mesh, a.dir)
    out = os.path.join(a.dir, "static.h5")
    print("bench_python_ksp: %s; OMP_NUM_THREADS=%s OPENBLAS_NUM_THREADS=%s; load %s" %
          (a.mesh, os.environ.get("OMP_NUM_THREADS"), os.environ.get("OPENBLAS_NUM_THREADS"), os.getloadavg()), flush=True)
    for r in range(a.rounds):
        wall, cpu, _ = timed([a.driver, "-problem", prob, "-bem_mat_type", "h2", "-o", out])
        with h5py.File(out, "r") as f:
            at = f.attrs
            print("round %d command line: iterations %d residual %.3e %s/%s wall_s %.2f cpu_s %.2f; load %.2f" %
                  (r, at["iterations"], at["residual"], at["ksp_type"], at["pc_type"], wall, cpu, os.getloadavg()[0]), flush=True)
        wall, cpu, text = timed([sys.executable, os.path.abspath(__file__), "--python-side", prob])
        print("round %d %s (process wall_s %.2f cpu_s %.2f); load %.2f" % (r, text.strip(), wall, cpu, os.getloadavg()[0]), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
