#!/usr/bin/python3
"""Command-line tests of -hssbem_progress (progress of long phases on rank 0's standard error).

Usage:
    /usr/bin/python3 test_progress_cli.py --driver PATH/hssbem --meshes REPO/meshes [--mpiexec mpiexec]
                                          [unittest arguments]

Built on test_cli.py's helpers. Small problems (an H2 run on sphere_l0, a four-frame scene on
cardioid_832, a three-frame contact scene on cube_l0) with -hssbem_progress_after 0, so that
phases far shorter than the default 2 s report: the phases are named on standard error, plain
lines when it is not a terminal and one updating line (carriage return, erase) when it is, none
with -hssbem_progress 0, none from rank 1, and the result file holds the same datasets and
attributes (timings aside) as a run without progress, with no progress text in it.
"""

import os
import pty
import re
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import test_cli as base  # noqa: E402

ON = ("-hssbem_progress", "1", "-hssbem_progress_after", "0")
OFF = ("-hssbem_progress", "0")
LINE = re.compile(r"^(?P<phase>[A-Za-z0-9 -]+): (?P<pct>\d+)% done, (?P<el>[0-9.]+) s elapsed(, about \d+ s left)?$")


def progress_lines(text):
    """(phase, percent) of every progress line in text (plain lines)."""
    out = []
    for line in text.splitlines():
        m = LINE.match(line)
        if m:
            out.append((m.group("phase"), int(m.group("pct"))))
    return out


def contents(h5):
    """Every dataset and every attribute of a result file, timings (and seconds) aside."""
    import h5py
    data = {}

    def visit(name, obj):
        if name.startswith("timings"):
            return
        if isinstance(obj, h5py.Dataset):
            data[name] = obj[()]
        for k, v in obj.attrs.items():
            if "seconds" not in k:
                data[name + "@" + k] = v

    with h5py.File(h5, "r") as f:
        f.visititems(visit)
        for k, v in f.attrs.items():
            if "seconds" not in k:
                data["@" + k] = v
    return data


class ProgressTests(base.CliTestCase):
    def h2_problem(self):
        return self.problem(mesh=self.copy_mesh("sphere_l0.msh"), material={"E": 1000.0, "nu": 0.3},
                            boundary=[{"where": "all", "pressure": 100.0}])

    def scene_problem(self):
        patch = [{"where": {"sphere": {"center": [0.45, 0.1 * i, 0.5], "radius": 0.3}}, "displacement": [-0.04, None, None]}
                 for i in range(4)]
        return self.problem(mesh=self.copy_mesh("cardioid_832.msh"), material={"lambda": 1000.0, "mu": 500.0},
                            boundary=[{"where": {"region": "base"}, "displacement": [0, 0, 0]}],
                            frames=[{"boundary": [p]} for p in patch])

    def contact_problem(self):
        table = {"name": "table", "plane": {"point": [0, 0, -0.005], "normal": [0, 0, 1]}}
        boundary = [{"where": {"region": "z1"}, "displacement": [None, None, -0.01]},
                    {"where": {"region": "x0"}, "displacement": [0, None, None]},
                    {"where": {"region": "y0"}, "displacement": [None, 0, None]}]
        return self.problem(mesh=self.copy_mesh("cube_l0.msh"), boundary=boundary, contact={"obstacles": [table]},
                            frames=[{"obstacles": {"table": {"translate": [0, 0, z]}}} for z in (0.0, 0.004, 0.008)])

    def run_pair(self, *args):
        """The problem run with and without progress; returns both runs, after checking that the
        result files hold the same contents and no progress text."""
        on = self.run_driver("-problem", "problem.json", "-o", self.path("on.h5"), *(args + ON), timeout=base.TIMEOUT_RUN)
        off = self.run_driver("-problem", "problem.json", "-o", self.path("off.h5"), *(args + OFF), timeout=base.TIMEOUT_RUN)
        self.assertSucceeds(on, self.path("on.h5"))
        self.assertSucceeds(off, self.path("off.h5"))
        import numpy as np
        a, b = contents(self.path("on.h5")), contents(self.path("off.h5"))
        self.assertEqual(sorted(a), sorted(b))
        self.assertGreater(len(a), 10)
        for k in a:
            x, y = np.asarray(a[k]), np.asarray(b[k])
            self.assertTrue(np.array_equal(x, y, equal_nan=x.dtype.kind in "fc"), k)  # NaN: no gap
        for name in ("on.h5", "on.xdmf"):
            with open(self.path(name), "rb") as f:
                self.assertNotIn(b"% done", f.read(), name)
        # Plain lines on standard error (a pipe), none on standard output, none when off.
        self.assertEqual(progress_lines(on.stdout), [], on.describe())
        self.assertNotIn("\r", on.stderr)
        self.assertEqual(progress_lines(off.output), [], off.describe())
        self.assertNotIn("% done", off.output)
        return on, off

    def assertPhases(self, result, *phases):
        lines = progress_lines(result.stderr)
        for phase in phases:
            pcts = [p for name, p in lines if name == phase]
            self.assertTrue(pcts, "no progress line of %r\n%s" % (phase, result.describe()))
            self.assertEqual(pcts.count(100), 1, "%r must end once\n%s" % (phase, result.describe()))
            self.assertEqual(pcts, sorted(pcts), phase)

    def test_h2_compression_factorization_and_gmres(self):
        self.h2_problem()
        on, _ = self.run_pair("-bem_mat_type", "h2")
        self.assertPhases(on, "H2 compression", "H2 factorization levels", "gmres")

    def test_scene_set_up_and_frames(self):
        self.scene_problem()
        on, _ = self.run_pair("-scene_strategy", "update")  # auto picks by timings measured at set-up
        self.assertPhases(on, "scene set-up", "scene frames")
        self.assertIn((("scene frames", 25)), progress_lines(on.stderr))  # after frame 0 of 4

    def test_contact_set_up_and_frames(self):
        self.contact_problem()
        on, _ = self.run_pair()
        self.assertPhases(on, "contact set-up", "contact frames")

    def test_rank_zero_only(self):
        self.h2_problem()
        r = self.run_driver("-problem", "problem.json", "-o", self.out, "-bem_mat_type", "h2", *ON, np=2, timeout=base.TIMEOUT_RUN)
        self.assertSucceeds(r, self.out)
        self.assertPhases(r, "H2 compression", "H2 factorization levels", "gmres")  # each ends once: rank 1 is silent

    def test_bad_threshold_is_one_clean_error(self):
        self.h2_problem()
        for value in ("-1", "nan"):
            with self.subTest(value=value):
                r = self.run_problem("problem.json", "-hssbem_progress_after", value)
                self.assertFailsCleanly(r, r"-hssbem_progress_after must be >= 0")
                self.assertErrorLine(r)

    def test_terminal_default_is_one_updating_line(self):
        # Without -hssbem_progress, on when standard error is a terminal: the line is rewritten in
        # place (carriage return, erase to the end) and a phase's end closes it with a newline.
        self.h2_problem()
        master, slave = pty.openpty()
        cmd = [base.DRIVER, "-problem", "problem.json", "-o", self.out, "-bem_mat_type", "h2", "-hssbem_progress_after", "0"]
        proc = subprocess.Popen(cmd, cwd=self.tmp, env=base.ENV, stdout=subprocess.PIPE, stderr=slave)
        os.close(slave)
        err = b""
        while True:
            try:
                chunk = os.read(master, 4096)
            except OSError:  # the terminal's other side closed
                break
            if not chunk:
                break
            err += chunk
        os.close(master)
        out = proc.communicate(timeout=base.TIMEOUT_RUN)[0].decode(errors="replace")
        err = err.decode(errors="replace")
        self.assertEqual(proc.returncode, 0, out + err)
        self.assertIn("\r\x1b[KH2 compression: 100% done", err)
        self.assertIn("\r\x1b[Kgmres: 100% done", err)
        self.assertNotIn("% done", out)


def main():
    base.ENV = dict(base.ENV, OMP_NUM_THREADS="1")  # the same arithmetic run to run
    base.run_suite(__doc__)


if __name__ == "__main__":
    main()
