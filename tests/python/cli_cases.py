#!/usr/bin/env python3
"""The problems the Python tests solve through hssbem and through the command line, and the
command line's results (the references the tests compare with).

    python3 cli_cases.py --driver build/bin/hssbem --mpiexec mpiexec --np 2 --out DIR

writes DIR/<case>_np<N>.h5 for every case (ctest runs it as the fixture of the Python suites;
a test at one rank runs a missing case itself).
"""
import argparse
import json
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
MESHES = os.environ.get("HSSBEM_MESHES", os.path.join(HERE, "..", "..", "meshes"))


def example(name):
    """A problem file of meshes/examples/ as a dict (its // comments dropped), the mesh path
    made absolute."""
    path = os.path.join(MESHES, "examples", name + ".json")
    with open(path) as f:
        text = "\n".join(line for line in f if not line.lstrip().startswith("//"))
    problem = json.loads(text)
    problem["mesh"] = os.path.normpath(os.path.join(MESHES, "examples", problem["mesh"]))
    problem.pop("output", None)
    return problem


def first_frames(problem, n):
    problem = dict(problem)
    problem["frames"] = problem["frames"][:n]
    return problem


def single_touch():
    """The organ under the instrument, once: no frames, the instrument lowered into the organ."""
    problem = example("organ_table_instrument")
    del problem["frames"]
    problem["contact"]["obstacles"][1]["sphere"]["center"][2] -= 0.05
    return problem


# name -> (problem dict, the command line's options)
CASES = {
    # cube_l0 in uniaxial tension (closed form u_z(z=1) = 0.01), dense operator + LU
    "cube_dense": (lambda: example("cube_tension"), ["-bem_mat_type", "dense"]),
    # sphere_l1 (998 vertices) under pressure, H² operator + GMRES + PC h2
    "sphere_h2": (lambda: example("sphere_pressure"), ["-bem_mat_type", "h2"]),
    # a scene: the cardioid's travelling contact patch, 3 frames
    "cardioid_scene": (lambda: first_frames(example("cardioid_moving_contact"), 3), []),
    # contact: the organ on the table under the instrument, 3 frames
    "organ_contact": (lambda: first_frames(example("organ_table_instrument"), 3), []),
    # contact's single solve: the same organ, the instrument pressed in, no frames
    "organ_touch": (single_touch, []),
}


def problem_file(case, out):
    """The case's problem written to out/<case>.json (the command line's input)."""
    path = os.path.join(out, case + ".json")
    with open(path, "w") as f:
        json.dump(CASES[case][0](), f)
    return path


def run_case(case, out, driver, np=1, mpiexec=None):
    """The command line's result of the case on np ranks: out/<case>_np<np>.h5."""
    os.makedirs(out, exist_ok=True)
    result = os.path.join(out, "%s_np%d.h5" % (case, np))
    command = [driver, "-problem", problem_file(case, out), "-o", result] + CASES[case][1]
    if np > 1 or mpiexec:
        command = [mpiexec or "mpiexec", "-n", str(np)] + (["--oversubscribe"] if np > 2 else []) + command
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
    done = subprocess.run(command, capture_output=True, text=True, env=env)
    if done.returncode != 0:
        raise RuntimeError("%s failed (%d): %s" % (" ".join(command), done.returncode, done.stderr.strip()))
    return result


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--driver", required=True)
    ap.add_argument("--mpiexec", default="mpiexec")
    ap.add_argument("--np", type=int, default=1)
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    for case in CASES:
        run_case(case, a.out, a.driver, a.np, a.mpiexec)
    return 0


if __name__ == "__main__":
    sys.exit(main())
