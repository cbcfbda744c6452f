"""hssbem from Python: 3D linear elastostatics by the boundary element method.

A thin client of hssbem's session layer, the engine behind the command line: the same problem
file grammar, the same table of options, the same results.

    import hssbem
    r = hssbem.solve("problem.json", {"bem_mat_type": "h2", "ksp_rtol": 1e-10})
    r.fields["displacement"]          # numpy (n, 3), as /fields/displacement of the result file
    r.write("result.h5")              # the file the command line writes

- solve(problem, options=None, comm=None) -> Result: a static problem (or a contact's single
  solve), solved once.
- Scene(problem, options=None, comm=None): a scene of frames or a contact, set up once and
  stepped frame by frame; its fields are numpy views that follow the frames.
- operator(problem, options=None, comm=None) -> (A, b): the BEM system as petsc4py objects;
  importing hssbem registers PC "hss" and "h2" for petsc4py's KSP.
- Error: every failure, with one line saying what is wrong.

A problem is a problem file's path or a dict in its grammar (docs/problem-file.md); its "mesh"
may be {"vertices": V, "triangles": T} with numpy arrays V (n, 3) and T (m, 3). Options are a
dict of the command line's options without the dash ({"ksp_rtol": 1e-10}) or a list of strings
(["-ksp_rtol", "1e-10"]); option_help() lists them. comm is an mpi4py communicator (default
COMM_WORLD): run `mpirun -n P python3 script.py` for a distributed solve. See docs/python.md.
"""

import json as _json
import numbers as _numbers
import os as _os
import sys as _sys

import numpy as _np


def _petsc():
    """PETSc as petsc4py initialised it: shared when the program initialised it already,
    else initialised here through petsc4py, so that hssbem and petsc4py use one PETSc."""
    import petsc4py
    if "petsc4py.PETSc" not in _sys.modules:
        petsc4py.init()
    from petsc4py import PETSc
    return PETSc


_PETSc = _petsc()

from . import _hssbem  # noqa: E402  (after PETSc is initialised)

_hssbem._initialize()

Error = _hssbem.Error
Error.__doc__ = """Every failure of hssbem: a bad problem, mesh, option or array, a solve that fails,
a file that cannot be written. str(e) is one line naming the problem (what the command line
prints after `hssbem: error:`)."""
Error.__module__ = "hssbem"

__version__ = _hssbem.__version__
__all__ = ["solve", "Result", "Scene", "operator", "Error", "option_help", "option_default"]


def option_help():
    """The options hssbem takes (its table of options), one line each with its default and range.
    The PETSc objects' own options (ksp_*, pc_*) are PETSc's."""
    return _hssbem.option_help()


def option_default(name):
    """The default of option `name` (without the dash): option_default("ksp_rtol") -> 1e-08."""
    return _hssbem.option_default(name)


# --- what the user gives, as the compiled part takes it -----------------------------------------

def _comm(comm):
    """The Fortran handle of an mpi4py (or petsc4py) communicator; None: COMM_WORLD."""
    if comm is None:
        return None
    if hasattr(comm, "tompi4py"):  # a petsc4py PETSc.Comm
        comm = comm.tompi4py()
    if not hasattr(comm, "py2f"):
        raise Error("comm: expected an mpi4py communicator, got %s" % type(comm).__name__)
    return comm.py2f()


def _option_value(name, value):
    if value is None:
        return None
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (str, _numbers.Number)):
        return str(value)
    raise Error("option %s: expected a number, a string or a bool, got %s" % (name, type(value).__name__))


def _is_value(token):
    """A token after an option name is its value unless it is the next option's name."""
    if not token.startswith("-"):
        return True
    try:
        float(token)
        return True
    except ValueError:
        return False


def _options(options):
    """[(name without the dash, value or None)] from a dict or a list of strings."""
    if options is None:
        return []
    out = []
    if isinstance(options, dict):
        for name, value in options.items():
            if not isinstance(name, str) or not name or name.startswith("-"):
                raise Error("options: %r: give the option's name without the dash, e.g. {\"ksp_rtol\": 1e-10}" % (name,))
            out.append((name, _option_value(name, value)))
        return out
    if isinstance(options, (list, tuple)):
        tokens = list(options)
        i = 0
        while i < len(tokens):
            t = tokens[i]
            if not isinstance(t, str) or not t.startswith("-") or len(t) < 2:
                raise Error("options: %r: expected an option's name with its dash, e.g. [\"-ksp_rtol\", \"1e-10\"]" % (t,))
            value = None
            if i + 1 < len(tokens) and isinstance(tokens[i + 1], str) and _is_value(tokens[i + 1]):
                value, i = tokens[i + 1], i + 1
            out.append((t[1:], value))
            i += 1
        return out
    raise Error("options: expected a dict or a list of strings, got %s" % type(options).__name__)


def _jsonable(value):
    if isinstance(value, _np.ndarray):
        return value.tolist()
    if isinstance(value, _np.generic):
        return value.item()
    raise TypeError("a %s is no value of the problem file's grammar" % type(value).__name__)


def _to_json(obj, what):
    try:
        return _json.dumps(obj, default=_jsonable, allow_nan=False)
    except ValueError:
        raise Error("%s: a value is not finite (NaN or infinity; null leaves a component as it was)" % what) from None
    except TypeError as e:
        raise Error("%s: %s" % (what, e)) from None


def _problem(problem):
    """The problem as the compiled part takes it: a path, or a dict's JSON and the mesh's arrays."""
    if isinstance(problem, (str, _os.PathLike)):
        return _hssbem.ProblemInput(_os.fspath(problem), "", None, None)
    if not isinstance(problem, dict):
        raise Error("problem: expected a problem file's path or a dict in its grammar, got %s" % type(problem).__name__)
    spec = dict(problem)
    vertices = triangles = None
    mesh = spec.get("mesh")
    if isinstance(mesh, dict):
        unknown = sorted(set(mesh) - {"vertices", "triangles"})
        if unknown or "vertices" not in mesh or "triangles" not in mesh:
            raise Error("problem: mesh: expected a path or {\"vertices\": V (n, 3), \"triangles\": T (m, 3)}"
                        + (" (unknown key %s)" % ", ".join(map(repr, unknown)) if unknown else ""))
        vertices, triangles = mesh["vertices"], mesh["triangles"]
        spec["mesh"] = "<arrays>"
    return _hssbem.ProblemInput("", _to_json(spec, "problem"), vertices, triangles)


# --- solve ---------------------------------------------------------------------------------------

class Result:
    """What a solve found: the datasets of the result file as numpy arrays (views of the solve's
    storage, no copies), by the names of the file's groups.

    fields      /fields: displacement (n, 3), traction (n, 3), traction_corner (m, 3, 3), stress
                (n, 6: xx yy zz yz xz xy), von_mises (n), principal_stress (n, 3), stress_corner
    interior    /interior: points, displacement, stress, von_mises, and "grid" when asked for
    contact     /contact: pressure, gap, status, forces (a dict by obstacle and body_<k>),
                iterations, active_vertices (a contact problem)
    reactions   /reactions: the force on each region (3,)
    bc          /bc: displacement_prescribed (n, 3) bool
    mesh        /mesh: vertices, triangles, triangle_region, sharp_vertex
    attributes  the root attributes (E, nu, iterations, residual, solver, ...)
    options     /options: the options the solve used
    timings     /timings: seconds per phase
    iterations  the solver's iterations (the contact's for a contact)

    With several ranks a static result is on every rank; a contact's is on rank 0 (the others
    hold empty dicts), as the command line runs contact on rank 0.
    """

    def __init__(self, compiled):
        self._r = compiled
        self._cache = {}

    def _get(self, name):
        if name not in self._cache:
            self._cache[name] = getattr(self._r, name)()
        return self._cache[name]

    fields = property(lambda self: self._get("fields"), doc="/fields: the surface fields by dataset name.")
    interior = property(lambda self: self._get("interior"), doc="/interior: the fields at the interior points (and grid).")
    contact = property(lambda self: self._get("contact"), doc="/contact: pressure, gap, status, forces, iterations.")
    reactions = property(lambda self: self._get("reactions"), doc="/reactions: the force on each region.")
    bc = property(lambda self: self._get("bc"), doc="/bc: displacement_prescribed per vertex and component.")
    mesh = property(lambda self: self._get("mesh"), doc="/mesh: vertices, triangles, triangle_region, sharp_vertex.")
    attributes = property(lambda self: self._get("attributes"), doc="The result file's root attributes.")
    options = property(lambda self: self._get("options"), doc="/options: the options the solve used, without the dash.")
    timings = property(lambda self: self._get("timings"), doc="/timings: seconds per phase.")

    @property
    def notices(self):
        """What the set-up noticed (a mesh reoriented, a pure-traction problem, ...)."""
        return list(self._r.notices)

    @property
    def iterations(self):
        """The solver's iterations (a contact: the contact iterations); None where not known."""
        if "iterations" in self.attributes:
            return self.attributes["iterations"]
        return self.contact.get("iterations")

    def write(self, path):
        """Write the result file `path` (HDF5, and its XDMF sidecar beside it): the same file as
        the command line writes. Collective: every rank calls it."""
        self._r.write(_os.fspath(path))

    def __repr__(self):
        return "<hssbem.Result %s, %d fields>" % (self.attributes.get("solver", "?"), len(self.fields))


def solve(problem, options=None, comm=None):
    """Solve a problem once, as the command line does, and return its Result.

    problem  a problem file's path, or a dict in its grammar (docs/problem-file.md) whose "mesh"
             may be {"vertices": V (n, 3) float, "triangles": T (m, 3) int}
    options  a dict of the command line's options without the dash, e.g. {"bem_mat_type": "h2",
             "ksp_rtol": 1e-10}, or a list of strings ["-bem_mat_type", "h2"]; an option nobody
             reads is an Error
    comm     an mpi4py communicator (default COMM_WORLD); every rank of it calls solve

    A static problem is solved on every rank; a contact (with "contact") once, on rank 0. A
    problem with "frames" is a scene: use Scene. When the problem names an "output" (or the
    option "o" does), the result file is written there too, as by the command line.
    Raises Error.
    """
    return Result(_hssbem.solve(_problem(problem), _options(options), _comm(comm)))


# --- scenes --------------------------------------------------------------------------------------

class Scene:
    """A scene of frames or a contact, set up once (the reference factorization), then stepped
    frame by frame; for simulators.

        scene = hssbem.Scene("organ.json")
        for k in range(100):
            report = scene.step({"obstacles": {"tool": {"translate": [0.01 * k, 0, 0]}}})
            draw(scene.fields["displacement"], scene.contact["pressure"])

    problem, options, comm: as for solve(). The problem needs "contact" or "frames", or a
    base that holds the body (each step then gives a frame of its own). stress=False leaves the
    surface stress out of each frame (faster).

    The work is done on rank 0 (as in the command line); every rank calls step().
    """

    def __init__(self, problem, options=None, comm=None, stress=True):
        self._s = _hssbem.Scene(_problem(problem), _options(options), _comm(comm), bool(stress))

    def step(self, frame):
        """Solve a frame and return its report (a dict: seconds, iterations, strategy, ...;
        contact: active_vertices). `frame` is a dict in the grammar of one element of "frames"
        ({"boundary": [...], "obstacles": {"name": {"translate": [dx, dy, dz]}}}) or the index
        of one of the problem's frames."""
        if isinstance(frame, bool) or not isinstance(frame, (dict, _numbers.Integral)):
            raise Error("frame: expected a dict in the grammar of one element of \"frames\" or a frame's index, got %s" % type(frame).__name__)
        return self._s.step(int(frame) if isinstance(frame, _numbers.Integral) else _to_json(frame, "frame"))

    @property
    def fields(self):
        """The last frame's surface fields per vertex (displacement, traction, stress, von_mises,
        principal_stress, displacement_prescribed): numpy views of the scene's storage, without
        copies, which the next step overwrites in place."""
        return self._s.fields()

    @property
    def contact(self):
        """The last frame's contact (pressure, gap, status: views as fields; forces by obstacle,
        iterations, active_vertices); empty without contact."""
        return self._s.contact()

    @property
    def mesh(self):
        """The surface the fields are given on: vertices (n, 3) and triangles (m, 3), 0-based,
        as the set-up checked and oriented them (views, on every rank)."""
        return self._s.mesh()

    @property
    def obstacles(self):
        """The names of the contact's obstacles, in the problem's order."""
        return list(self._s.obstacles)

    @property
    def num_frames(self):
        """The number of frames the problem itself has (step(i) solves frame i)."""
        return self._s.num_frames

    def haptic_forces(self, obstacles):
        """The haptic call between frames: each obstacle's force on the bodies (a dict by name of
        (3,) arrays) with obstacles moved to new poses: {"name": [dx, dy, dz]} (a translation
        from the base position) or, as in a frame, {"name": {"translate": [...], "rotate":
        {"axis": [...], "angle": degrees}}}; the others stay where the last frame put them. Uses
        the last frame's contact points and active set: one small solve, no new frame."""
        if not isinstance(obstacles, dict):
            raise Error("haptic_forces: expected a dict by obstacle name, got %s" % type(obstacles).__name__)
        poses = {}
        for name, value in obstacles.items():
            if not isinstance(value, dict):
                value = {"translate": value}
            poses[name] = value
        return self._s.haptic_forces(_to_json(poses, "haptic_forces"))


# --- the operator for petsc4py ------------------------------------------------------------------

def operator(problem, options=None, comm=None):
    """The BEM system A x = b of a static problem as petsc4py objects: A a PETSc.Mat (dense, or
    the MatShell of the H² or HSS operator, per bem_mat_type), b its right-hand side PETSc.Vec.

        A, b = hssbem.operator("problem.json", {"bem_mat_type": "h2"})
        ksp = PETSc.KSP().create(A.getComm()); ksp.setOperators(A)
        ksp.setType("gmres"); ksp.getPC().setType("h2")   # hssbem's H² factorization as PC
        x = b.duplicate(); ksp.solve(b, x)

    x holds the unknowns, 3 per dof node (traction where the displacement is prescribed,
    displacement elsewhere); on several ranks the compressed systems order the rows by clusters
    (A's layout, as b's). A keeps the problem alive. Raises Error.
    """
    return _hssbem.operator(_problem(problem), _options(options), _comm(comm))
