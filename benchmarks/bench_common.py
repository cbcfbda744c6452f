"""Helpers shared by the benchmark scripts (bench_dense.py, bench_hss.py, bench_persistence.py,
bench_h2_persistence.py): mesh sizes, argument parsing, machine description, log tails, timed
driver runs and the figures they print."""
import argparse
import os
import platform
import re
import subprocess
import sys


def triangles_for_unknowns(n):
    """A closed surface of genus 0 with T triangles has T/2 + 2 vertices, 3 unknowns each, so
    T = 2 (N/3 - 2); rounded to an even count."""
    t = int(round(2.0 * (n / 3.0 - 2.0)))
    return max(20, t + (t % 2))


def parse_int_list(text, what=None):
    """'3000,6000,1e4' -> [3000, 6000, 10000] (positive integers); `what` names the option in errors."""
    prefix = f"{what}: " if what else ""
    try:
        vals = [int(float(s)) for s in text.replace(" ", "").split(",") if s]
    except ValueError:
        raise argparse.ArgumentTypeError(f"{prefix}expected a comma-separated list of integers, got {text!r}")
    if not vals or any(v <= 0 for v in vals):
        raise argparse.ArgumentTypeError(f"{prefix}need positive integers, got {text!r}")
    return vals


def available_cores():
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover
        return os.cpu_count() or 1


def cpu_model():
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown CPU"


def tail(path, lines=25, width=None):
    """The last lines of a text file (for failure reports), each cut to width characters when
    given (PETSc's configure line is huge)."""
    try:
        with open(path, errors="replace") as f:
            out = f.readlines()[-lines:]
    except OSError:
        return ""
    return "".join(l if width is None or len(l) <= width else l[:width] + " [...]\n" for l in out)


def timed_run(driver, prob, out, extra, ranks=1):
    """(wall s, CPU s (user + system, every thread; with ranks > 1 what mpiexec's process tree
    reports to /usr/bin/time), stdout) of one run of the driver; exits with its output when it
    fails."""
    cmd = ["/usr/bin/time", "-f", "%e %U %S"]
    if ranks > 1:
        cmd += ["mpiexec", "-n", str(ranks), "--oversubscribe"]
    cmd += [driver, "-problem", prob, "-o", out] + extra
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, universal_newlines=True)
    if p.returncode != 0:
        sys.exit("failed: %s\n%s\n%s" % (" ".join(cmd), p.stdout, p.stderr))
    wall, user, system = p.stderr.strip().splitlines()[-1].split()
    return float(wall), float(user) + float(system), p.stdout


def figure(pattern, text):
    """The number the regular expression's first group finds in text (NaN when absent)."""
    m = re.search(pattern, text)
    return float(m.group(1)) if m else float("nan")
