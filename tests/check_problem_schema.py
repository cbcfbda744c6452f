#!/usr/bin/env python3
"""ctest problem_schema: the problem file's JSON Schema (docs/problem-file.schema.json) against
what ships and against files the driver refuses.

  tests/check_problem_schema.py [--driver build/bin/hssbem]

1. Every shipped problem (meshes/examples/*.json) and every whole problem file shown in
   docs/problem-file.md and README.md (```jsonc blocks that open with '{') is valid.
2. Each file of INVALID (a valid base with one fault) is rejected, with a fault at the JSON path
   the driver names; with --driver, the driver refuses it too, naming that path, so the cases
   are faults of the real parser and not of the schema alone.
3. Comments are stripped as the driver strips them ('//' inside a string is not a comment).
Prints one line per failure and exits 1 on any.
"""
import argparse
import concurrent.futures
import copy
import json
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "scripts"))
import problem_schema  # noqa: E402

BASE = {"mesh": "sphere.msh", "material": {"E": 1000.0, "nu": 0.3},
        "boundary": [{"where": {"region": "clamp"}, "displacement": [0, 0, 0]}]}
PLANE = {"name": "table", "plane": {"point": [0, 0, -1], "normal": [0, 0, 1]}}


def with_(path, value):
    """BASE with the value at path (a list of keys and indices) set, or removed when value is DROP."""
    doc = copy.deepcopy(BASE)
    node = doc
    for key in path[:-1]:
        node = node.setdefault(key, {}) if isinstance(key, str) else node[key]
    if value is DROP:
        del node[path[-1]]
    else:
        node[path[-1]] = value
    return doc


DROP = object()

# (what, the file, the JSON path of the fault as the driver names it[, what the driver's line says
# instead, for a value it checks after the command line's overrides])
INVALID = [
    ("unknown top-level key", with_(["outptu"], "r.h5"), "(top level)"),
    ("no mesh", with_(["mesh"], DROP), "(top level)"),
    ("empty mesh path", with_(["mesh"], ""), "mesh"),
    ("E without nu", with_(["material"], {"E": 1000.0}), "material"),
    ("both material forms", with_(["material"], {"E": 1.0, "nu": 0.3, "mu": 1.0}), "material"),
    ("nu of 0.5", with_(["material", "nu"], 0.5), "material.nu", "nu = 0.5"),
    ("a rule without where", with_(["boundary", 0], {"displacement": [0, 0, 0]}), "boundary[0]"),
    ("two values in one rule", with_(["boundary", 0, "traction"], [1, 0, 0]), "boundary[0]"),
    ("two selectors", with_(["boundary", 0, "where"], {"region": "a", "box": [[0, 0, 0], [1, 1, 1]]}), "boundary[0].where"),
    ("unknown selector word", with_(["boundary", 0, "where"], "everywhere"), "boundary[0].where"),
    ("region tag 0", with_(["boundary", 0, "where"], {"region": 0}), "boundary[0].where.region"),
    ("a row of two", with_(["boundary", 0, "displacement"], [0, 0]), "boundary[0].displacement"),
    ("a value beyond 1e30", with_(["boundary", 0, "displacement"], [0, 0, 1e31]), "boundary[0].displacement"),
    ("a null pressure", with_(["boundary", 0], {"where": "all", "pressure": None}), "boundary[0].pressure"),
    ("negative vertex index", with_(["boundary", 0, "where"], {"vertices": [0, -1]}), "boundary[0].where.vertices"),
    ("empty frames", with_(["frames"], []), "frames"),
    ("an empty frame", with_(["frames"], [{}]), "frames[0]"),
    ("a frame's unknown key", with_(["frames"], [{"boundary": [], "rules": []}]), "frames[0]"),
    ("a grid of 0 cells", with_(["interior_points"], {"grid": {"box": [[0, 0, 0], [1, 1, 1]], "cells": [0, 4, 4]}}),
     "interior_points.grid.cells[0]"),
    ("an interior point of two", with_(["interior_points"], [[0, 0]]), "interior_points"),
    ("contact's unknown key", with_(["contact"], {"obstacle": []}), "contact"),
    ("negative friction", with_(["contact"], {"friction": -0.1}), "contact.friction"),
    ("bodies as a number", with_(["contact"], {"bodies": 1}), "contact.bodies"),
    ("an obstacle without a shape", with_(["contact"], {"obstacles": [{"name": "t"}]}), "contact.obstacles[0]"),
    ("an obstacle with two shapes", with_(["contact"], {"obstacles": [dict(PLANE, sphere={"center": [0, 0, 0], "radius": 1})]}),
     "contact.obstacles[0]"),
    ("a sphere obstacle of radius 0", with_(["contact"], {"obstacles": [{"name": "s", "sphere": {"center": [0, 0, 0], "radius": 0}}]}),
     "contact.obstacles[0].sphere.radius"),
    ("gravity without density", with_(["gravity"], [0, 0, -9.81]), "material", "gravity needs the material's 'density'"),
    ("a frame's gravity without density", with_(["frames"], [{"gravity": [0, -9.81, 0]}]), "material", "frames[0].gravity: gravity needs"),
    ("negative density", dict(with_(["material", "density"], -1.0), gravity=[0, 0, -9.81]), "material.density"),
    ("gravity of two components", dict(with_(["material", "density"], 1000.0), gravity=[0, -9.81]), "gravity"),
    ("a frame's gravity beyond 1e30", dict(with_(["material", "density"], 1000.0), frames=[{"gravity": [0, 0, -1e31]}]), "frames[0].gravity[2]"),
    ("a placement without translate or rotate", dict(with_(["contact"], {"obstacles": [PLANE]}), frames=[{"obstacles": {"table": {}}}]),
     "frames[0].obstacles.table"),
]

# Text-level faults (the schema never sees them: the loader refuses them as the parser does).
INVALID_TEXT = [
    ("duplicate key", '{"mesh": "a.msh", "mesh": "b.msh", "material": {"E": 1, "nu": 0.3}}', "duplicate key"),
    ("unterminated comment", '{"mesh": "a.msh", /* "material": {"E": 1, "nu": 0.3}}', "comment"),
    ("a number beyond double", '{"mesh": "a.msh", "material": {"E": 1e999, "nu": 0.3}}', "not finite"),
]

COMMENTED = """// a problem file with comments
{
  "mesh": "http://not-a-comment.msh",   // '//' inside a string stays
  /* a block
     comment */ "material": {"E": 1000.0, /* inline */ "nu": 0.3},
  "boundary": [{"where": "all", "displacement": [0, 0, 0]}]
}
"""


def shipped_problems():
    yield from sorted((ROOT / "meshes" / "examples").glob("*.json"))


def documented_problems():
    """(page, index, text) of each whole problem file a page shows."""
    for page in (ROOT / "docs" / "problem-file.md", ROOT / "README.md"):
        blocks = re.findall(r"^```jsonc?\n(.*?)^```", page.read_text(encoding="utf-8"), flags=re.S | re.M)
        for k, block in enumerate(blocks):
            if block.lstrip().startswith("{") and '"mesh"' in block:
                yield page.relative_to(ROOT).as_posix(), k, block


def check_valid(check):
    failures, count = [], 0
    for path in shipped_problems():
        count += 1
        failures += [f"{path.relative_to(ROOT).as_posix()}: {f}" for f in problem_schema.check_file(path, check)]
    for page, k, text in documented_problems():
        count += 1
        try:
            failures += [f"{page}, code block {k}: {f}" for f in problem_schema.faults(problem_schema.loads(text), check)]
        except problem_schema.ProblemFileError as e:
            failures.append(f"{page}, code block {k}: {e}")
    if count < 9:
        failures.append(f"only {count} valid problems found (the shipped examples and the documented files)")
    return failures, count


def names_path(faults, path):
    """A fault at path or inside it (the schema may name the component, the driver its vector)."""
    places = [f.split(": ", 1)[0] for f in faults]
    return any(p == path or p.startswith(path + "[") or p.startswith(path + ".") for p in places)


def check_invalid(check):
    failures = []
    for what, doc, path, *_ in INVALID:
        faults = problem_schema.faults(doc, check)
        if not faults:
            failures.append(f"invalid case '{what}': accepted by the schema")
        elif not names_path(faults, path):
            failures.append(f"invalid case '{what}': no fault at {path} (faults: {faults})")
    for what, text, words in INVALID_TEXT:
        try:
            problem_schema.loads(text)
            failures.append(f"invalid text '{what}': accepted")
        except problem_schema.ProblemFileError as e:
            if words not in str(e):
                failures.append(f"invalid text '{what}': refused as '{e}', expected '{words}'")
    return failures


def check_comments(check):
    try:
        doc = problem_schema.loads(COMMENTED)
    except problem_schema.ProblemFileError as e:
        return [f"commented file: {e}"]
    failures = [f"commented file: {f}" for f in problem_schema.faults(doc, check)]
    if doc.get("mesh") != "http://not-a-comment.msh":
        failures.append(f"commented file: '//' inside a string was stripped: mesh = {doc.get('mesh')!r}")
    return failures


def driver_refuses(driver, text, says, workdir):
    """None if the driver ends with an error line that contains says; else what it did."""
    problem = Path(workdir) / "problem.json"
    problem.write_text(text, encoding="utf-8")
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1", OMP_NUM_THREADS="1")
    run = subprocess.run([os.path.abspath(driver), "-problem", str(problem)], cwd=workdir, env=env, capture_output=True, text=True,
                         timeout=60)
    out = run.stdout + run.stderr
    if run.returncode != 0 and "hssbem: error:" in out and says in out:
        return None
    return f"exit {run.returncode}, output: {out.strip()[:300]}"


def driver_cases():
    """(what, text, what the driver's error line must contain) of every invalid case."""
    for what, doc, path, *says in INVALID:
        yield f"invalid case '{what}'", json.dumps(doc), says[0] if says else ("problem.json: " if path == "(top level)" else f": {path}")
    for what, text, _ in INVALID_TEXT:
        yield f"invalid text '{what}'", text, "problem.json"


def check_driver(driver):
    """Each case in a directory of its own, a few at a time (a run mostly waits for MPI's start)."""
    def run(case):
        what, text, says = case
        with tempfile.TemporaryDirectory() as workdir:
            problem = driver_refuses(driver, text, says, workdir)
        return f"{what}: the driver did not refuse it naming '{says}': {problem}" if problem else None

    with concurrent.futures.ThreadPoolExecutor(max_workers=6) as pool:
        return [f for f in pool.map(run, driver_cases()) if f]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--driver", help="the hssbem driver: check that it refuses the invalid cases too")
    args = parser.parse_args()
    try:
        check = problem_schema.validator()
    except ImportError:
        print("check_problem_schema: python3-jsonschema is missing (scripts/install_deps.sh)")
        return 1
    valid_failures, valid = check_valid(check)
    failures = valid_failures + check_invalid(check) + check_comments(check)
    if args.driver:
        failures += check_driver(args.driver)
    for f in failures:
        print(f)
    if failures:
        return 1
    cases = len(INVALID) + len(INVALID_TEXT)
    print(f"problem_schema: {valid} valid problems accepted, {cases} invalid ones refused"
          + (" (by the driver too)" if args.driver else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())
