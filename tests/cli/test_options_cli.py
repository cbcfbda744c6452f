#!/usr/bin/python3
"""Command-line tests of the table of options (include/hssbem/core/option_table.def): -help,
-version, and the options a run records in its result file.

Usage:
    /usr/bin/python3 test_options_cli.py --driver PATH/hssbem --meshes REPO/meshes [--mpiexec mpiexec]
                                         [unittest arguments, e.g. HelpTests]

The harness is test_cli.py's; the table is read from the repository by scripts/option_table.py.
HelpTests: -help lists every row with the table's default and its range, section by section,
each in the sections of its jobs; with -problem, those of the file's job. RecordTests: a static
solve (dense and H2), a scene and a contact run with the defaults record, under /options, every
option of their job with the table's default (the same values -help shows), and a value given on
the command line instead. VersionTests: -version and --version.
"""

import os
import re
import shutil
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "..", "..", "scripts"))
import option_table  # noqa: E402
import test_cli  # noqa: E402
from test_cli import CliTestCase, TIMEOUT_RUN  # noqa: E402

ROOT = os.path.join(HERE, "..", "..")
ROWS = [r for r in option_table.read_rows(ROOT) if not r["keyless"]]
JOBS = {"static": "kStatic", "scene": "kScene", "contact": "kContact"}


def applies(row, job):
    return row["jobs"].strip() == "kEvery" or JOBS[job] in row["jobs"]


def same_value(row, recorded):
    d = row["default"]
    if isinstance(d, bool):
        return int(recorded) == int(d)
    if isinstance(d, str):
        return (recorded.decode() if isinstance(recorded, bytes) else str(recorded)) == d
    return float(recorded) == float(d)


def normal(text):
    """A range's text with its numbers as floats and its separators as commas (-help prints
    1e+06 where the table says 1e6, and choices with bars)."""
    text = text.replace("|", ",").replace(", ", ",")
    return re.sub(r"-?\d+(?:\.\d*)?(?:e[-+]?\d+)?", lambda m: repr(float(m.group(0))), text)


def help_lines(output):
    """{name: (default, rest)} of the driver's table lines "  -name <default>: help [range]"."""
    out = {}
    for m in re.finditer(r"(?m)^  -(\w+) <([^>]*)>: (.*)$", output):
        out.setdefault(m.group(1), (m.group(2), m.group(3)))
    return out


class HelpTests(CliTestCase):
    def test_help_lists_every_row_with_the_tables_default_and_range(self):
        r = self.run_driver("-help")
        self.assertEqual(r.returncode, 0, r.describe())
        self.assertNotRegex(r.output, r"hssbem: error", r.describe())
        lines = help_lines(r.stdout)
        self.assertGreaterEqual(len(ROWS), 60)
        for row in ROWS:
            with self.subTest(option=row["name"]):
                self.assertIn(row["name"], lines, "-help does not list -%s" % row["name"])
                default, rest = lines[row["name"]]
                self.assertEqual(default, option_table.shown(row, empty=""))
                self.assertTrue(rest.startswith(row["help"]), rest)
                values = option_table.values_text(row)
                if values:
                    self.assertTrue(normal(rest).endswith("[" + normal(values) + "]"), "%s: %s" % (values, rest))
        # PC h2's own lines, as PETSc prints them when its KSP reads them, show the same default.
        self.assertRegex(r.stdout, r"-pc_h2_rel_tol <0\.002 : 0\.002>")
        self.assertEqual(self.leftovers(), [])

    def test_help_with_a_problem_lists_its_jobs_options_and_runs(self):
        self.write_cube()
        self.problem()
        r = self.run_problem("problem.json", "-help", "-bem_mat_type", "dense", timeout=TIMEOUT_RUN)
        self.assertSucceeds(r, self.out)
        lines = help_lines(r.stdout)
        for row in ROWS:
            with self.subTest(option=row["name"]):
                self.assertEqual(row["name"] in lines, applies(row, "static"))


class RecordTests(CliTestCase):
    def recorded(self, h5):
        import h5py
        with h5py.File(h5, "r") as f:
            return dict(f["/options"].attrs)

    def assertDefaults(self, h5, job, at_least, given=()):
        """Every recorded option of the job is a row of it with the table's default (those in
        `given` excepted), and at least `at_least` are recorded."""
        rec = self.recorded(h5)
        by_name = {r["name"]: r for r in ROWS}
        self.assertGreaterEqual(len(rec), at_least, sorted(rec))
        for name, value in rec.items():
            with self.subTest(option=name):
                self.assertIn(name, by_name)
                self.assertTrue(applies(by_name[name], job), name)
                if name in given or by_name[name]["shown"]:
                    continue
                self.assertTrue(same_value(by_name[name], value), "%s: recorded %r, the table's %r" % (name, value, by_name[name]["default"]))
        return rec

    def test_static_dense_and_h2_record_the_defaults_they_used(self):
        self.write_cube()
        self.problem()
        r = self.run_problem("problem.json", "-bem_mat_type", "dense", timeout=TIMEOUT_RUN)
        self.assertSucceeds(r, self.out)
        self.assertDefaults(self.out, "static", 25, given=("bem_mat_type",))
        shutil.copy(os.path.join(test_cli.MESHES, "sphere_l0.msh"), self.path("sphere_l0.msh"))
        self.problem(mesh="sphere_l0.msh", name="sphere.json")
        h2 = self.path("h2.h5")
        r = self.run_driver("-problem", "sphere.json", "-o", h2, "-bem_mat_type", "h2", "-mat_h2_leaf_size", "16", timeout=TIMEOUT_RUN)
        self.assertSucceeds(r, h2)
        rec = self.assertDefaults(h2, "static", 35, given=("bem_mat_type", "mat_h2_leaf_size"))
        self.assertEqual(int(rec["mat_h2_leaf_size"]), 16)
        for name in ("ksp_rtol", "ksp_gmres_restart", "pc_h2_rel_tol", "pc_h2_top_size", "pc_h2_single_top_from", "mat_h2_rel_tol", "mat_h2_single_precision"):
            self.assertIn(name, rec)

    def test_values_given_on_the_command_line_are_recorded(self):
        shutil.copy(os.path.join(test_cli.MESHES, "sphere_l0.msh"), self.path("sphere_l0.msh"))
        self.problem(mesh="sphere_l0.msh")
        r = self.run_problem("problem.json", "-bem_mat_type", "h2", "-mat_h2_leaf_size", "16", "-mat_h2_rel_tol", "1e-4", "-pc_h2_rel_tol", "5e-3",
                             "-ksp_rtol", "1e-9", "-bem_interior_band", "0.5", timeout=TIMEOUT_RUN)
        self.assertSucceeds(r, self.out)
        rec = self.recorded(self.out)
        self.assertEqual(rec["mat_h2_rel_tol"], 1e-4)
        self.assertEqual(rec["pc_h2_rel_tol"], 5e-3)
        self.assertEqual(rec["ksp_rtol"], 1e-9)
        self.assertEqual(rec["bem_interior_band"], 0.5)
        self.assertEqual(rec["bem_mat_type"].decode() if isinstance(rec["bem_mat_type"], bytes) else rec["bem_mat_type"], "h2")

    def test_a_scene_and_a_contact_record_the_defaults_they_used(self):
        base, patch = test_cli.SceneTests.BASE, test_cli.SceneTests.patch
        self.problem(mesh=self.copy_mesh("cardioid_832.msh"), material={"lambda": 1000.0, "mu": 500.0}, boundary=base,
                     frames=[{"boundary": patch(0.0, 0.04)}, {"boundary": patch(0.2, 0.045)}], name="scene.json")
        r = self.run_problem("scene.json", timeout=TIMEOUT_RUN)
        self.assertSucceeds(r, self.out)
        self.assertDefaults(self.out, "scene", 10)
        self.problem(mesh=self.copy_mesh("cube_l0.msh"), name="contact.json",
                     boundary=[{"where": {"region": "z1"}, "displacement": [None, None, -0.01]}, {"where": {"region": "x0"}, "displacement": [0, None, None]},
                               {"where": {"region": "y0"}, "displacement": [None, 0, None]}],
                     contact={"obstacles": [{"name": "table", "plane": {"point": [0, 0, 0], "normal": [0, 0, 1]}}]})
        out = self.path("contact.h5")
        r = self.run_driver("-problem", "contact.json", "-o", out, timeout=TIMEOUT_RUN)
        self.assertSucceeds(r, out)
        rec = self.assertDefaults(out, "contact", 25)
        for name in ("contact_tol", "contact_max_it", "contact_h2_rtol", "contact_h2_factor_tol", "mat_h2_rel_tol"):
            self.assertIn(name, rec)


class VersionTests(CliTestCase):
    def test_version_prints_the_versions_and_exits_zero(self):
        for flag in ("-version", "--version"):
            with self.subTest(flag=flag):
                r = self.run_driver(flag)
                self.assertEqual(r.returncode, 0, r.describe())
                self.assertRegex(r.stdout, r"(?m)^hssbem \d+\.\d+\.\d+ \(git [0-9a-f]{7,}(-dirty)?|unknown, \w+ build\)")
                self.assertRegex(r.stdout, r"(?m)^hssbem .* build\)$")
                self.assertRegex(r.stdout, r"(?m)^Petsc Release Version 3\.\d+")
                self.assertRegex(r.stdout, r"(?m)^MPI: \S+")
                self.assertRegex(r.stdout, r"(?m)^HDF5 \d+\.\d+\.\d+$")
                self.assertNotRegex(r.output, r"hssbem: error|PETSc Team")

    def test_version_on_two_ranks_prints_once(self):
        if not test_cli.MPIEXEC:
            self.skipTest("no mpiexec")
        r = self.run_driver("-version", np=2)
        self.assertEqual(r.returncode, 0, r.describe())
        self.assertEqual(len(re.findall(r"(?m)^hssbem \d", r.stdout)), 1, r.describe())


def main():
    test_cli.run_suite(__doc__)


if __name__ == "__main__":
    main()
