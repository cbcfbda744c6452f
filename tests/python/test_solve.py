"""hssbem.solve: the same problem through Python and through the command line gives the same
result file (dense: identical datasets; H²: identical iterations), from a file, a dict or arrays."""
import os

import numpy as np
import pytest

import hssbem
from conftest import COMM, assert_identical, attributes, datasets, options, problem, reference


def test_static_dense_identical_to_command_line(shared_tmp):
    """cube_l0 in tension, dense: every dataset of /fields, /interior, /reactions and /bc the
    same as the command line's, in Result and in the file Result.write() writes; and the closed
    form u_z(z = 1) = s / E = 0.01 (the discretisation's error on cube_l0 is about 1 %)."""
    ref = reference("cube_dense")
    r = hssbem.solve(problem("cube_dense"), options("cube_dense"))
    out = os.path.join(shared_tmp, "cube.h5")
    r.write(out)
    if COMM.rank != 0:
        return
    for group in ("fields", "interior", "reactions", "bc", "mesh"):
        want = datasets(ref, group)
        assert want, group
        assert datasets(out, group).keys() == want.keys(), group
        for name, value in want.items():
            assert_identical(datasets(out, group)[name], value, "/%s/%s (written)" % (group, name))
    for name, value in datasets(ref, "fields").items():
        assert_identical(r.fields[name], value, "Result.fields[%s]" % name)
    for name in ("points", "displacement", "stress", "von_mises"):
        assert_identical(r.interior[name], datasets(ref, "interior")[name], "Result.interior[%s]" % name)
    for region, force in datasets(ref, "reactions").items():
        assert_identical(r.reactions[region], force, "Result.reactions[%s]" % region)
    assert r.iterations == attributes(ref)["iterations"]
    top = np.abs(r.mesh["vertices"][:, 2] - 1) < 1e-12
    assert top.sum() > 10
    uz = r.fields["displacement"][top, 2]
    assert np.all(np.abs(uz - 0.01) < 0.03 * 0.01), uz


def test_h2_iterations_identical_to_command_line():
    """sphere_l1 under pressure with the H² operator (GMRES + PC h2): the command line's
    iterations, and its displacement to the solver's tolerance."""
    ref = reference("sphere_h2")
    r = hssbem.solve(problem("sphere_h2"), options("sphere_h2"))
    if COMM.rank != 0:
        return
    want = attributes(ref)
    assert r.attributes["mat_type"] == "h2" and r.attributes["pc_type"] == "h2"
    assert r.iterations == want["iterations"] and r.iterations >= 1
    u, u_ref = r.fields["displacement"], datasets(ref, "fields")["displacement"]
    assert np.linalg.norm(u - u_ref) <= 1e-6 * np.linalg.norm(u_ref)


def test_contact_single_solve_identical_to_command_line():
    """A contact solved once (no frames): /contact (pressure, gap, status, forces) and /fields as
    the command line's, on rank 0 where the contact runs."""
    ref = reference("organ_touch")
    r = hssbem.solve(problem("organ_touch"))
    if COMM.rank != 0:
        assert r.fields == {} and not r._r.on_every_rank
        return
    want = datasets(ref, "contact")
    for name in ("pressure", "gap", "status"):
        assert_identical(r.contact[name], want[name], "/contact/" + name)
    for name, force in r.contact["forces"].items():
        assert_identical(force, want["forces/" + name], "/contact/forces/" + name)
    assert r.contact["active_vertices"] > 0 and r.contact["forces"]["tool"][2] < 0
    for name, value in datasets(ref, "fields").items():
        assert_identical(r.fields[name], value, "/fields/" + name)
    assert r.iterations == attributes(ref, "/contact")["iterations"]


def cube_by_boxes(mesh):
    """cube_tension with its regions as boxes (a mesh made of arrays has no regions)."""
    p = problem("cube_dense")
    p["mesh"] = mesh
    p["boundary"] = [
        {"where": {"box": [[-1, -1, -0.001], [2, 2, 0.001]]}, "displacement": [None, None, 0]},
        {"where": {"box": [[-1, -1, 0.999], [2, 2, 1.001]]}, "traction": [0, 0, 10.0]},
        {"where": {"vertices": [0]}, "displacement": [0, 0, 0]},
        {"where": {"vertices": [73]}, "displacement": [None, 0, None]},
    ]
    return p


def test_mesh_from_arrays_identical_to_mesh_file():
    """The same mesh given as numpy arrays (float32 vertices and int32 triangles too) or as a
    file: identical fields."""
    from_file = hssbem.solve(cube_by_boxes(problem("cube_dense")["mesh"]), {"bem_mat_type": "dense"})
    V, T = np.array(from_file.mesh["vertices"]), np.array(from_file.mesh["triangles"])
    from_arrays = hssbem.solve(cube_by_boxes({"vertices": V, "triangles": T.astype(np.int64)}), {"bem_mat_type": "dense"})
    for name in ("displacement", "traction", "stress"):
        assert_identical(from_arrays.fields[name], from_file.fields[name], name)
    from_lists = hssbem.solve(cube_by_boxes({"vertices": V.tolist(), "triangles": T.astype(np.int32)}), ["-bem_mat_type", "dense"])
    assert_identical(from_lists.fields["displacement"], from_file.fields["displacement"], "lists")
    assert np.abs(from_file.fields["displacement"]).max() > 1e-3


def test_result_arrays_are_views():
    """Result's arrays are views of the solve's storage (no copies), alive with the result."""
    r = hssbem.solve(problem("cube_dense"), options("cube_dense"))
    a, b = r._r.fields()["displacement"], r._r.fields()["displacement"]
    assert np.shares_memory(a, b) and not a.flags.owndata
    del r
    assert np.isfinite(a).all()


BAD = [
    # (problem, options, what the one line says)
    (lambda: {"mesh": problem("cube_dense")["mesh"]}, None, "missing 'material'"),
    (lambda: dict(problem("cube_dense"), boundary=[{"where": {"region": "nowhere"}, "displacement": [0, 0, 0]}]), None, "nowhere"),
    (lambda: dict(problem("cube_dense"), colour="red"), None, "colour"),
    (lambda: dict(problem("cube_dense"), mesh={"vertices": np.zeros((4, 2)), "triangles": np.zeros((4, 3), int)}), None, "mesh.vertices: expected shape (n, 3), got (4, 2)"),
    (lambda: dict(problem("cube_dense"), mesh={"vertices": np.zeros((4, 3)), "triangles": np.zeros((4, 3))}), None, "mesh.triangles: expected integers, got dtype float64"),
    (lambda: dict(problem("cube_dense"), mesh={"vertices": np.zeros(12), "triangles": np.zeros((4, 3), int)}), None, "got (12,)"),
    (lambda: dict(problem("cube_dense"), mesh={"vertices": [[0, 0, 0], [1, 0, np.nan], [0, 1, 0], [0, 0, 1]],
                                               "triangles": [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]}), None, "vertex 1 has a non-finite coordinate"),
    (lambda: dict(problem("cube_dense"), mesh={"vertices": np.eye(3), "triangles": [[0, 1, 2]]}), None, "mesh '<arrays>'"),
    (lambda: dict(problem("cube_dense"), mesh={"points": 1}), None, "unknown key 'points'"),
    (lambda: dict(problem("cube_dense"), boundary=[{"where": "all", "traction": [0, 0, np.inf]}]), None, "not finite"),
    (lambda: 42, None, "expected a problem file's path or a dict"),
    (lambda: "/nonexistent/problem.json", None, "cannot open problem file"),
    (lambda: problem("cube_dense"), {"ksp_rtoll": 1e-9}, "-ksp_rtoll"),
    (lambda: problem("cube_dense"), {"bem_mat_type": "fast"}, "bem_mat_type"),
    (lambda: problem("cube_dense"), {"mat_h2_rel_tol": 2}, "mat_h2_rel_tol"),
    (lambda: problem("cube_dense"), {"-ksp_rtol": 1e-9}, "without the dash"),
    (lambda: problem("cube_dense"), ["ksp_rtol", "1e-9"], "with its dash"),
    (lambda: problem("cube_dense"), 3, "expected a dict or a list"),
]


@pytest.mark.parametrize("case", range(len(BAD)))
def test_errors_are_one_line(case):
    """Bad input: an hssbem.Error with one line naming the problem; the interpreter goes on."""
    make, opts, says = BAD[case]
    with pytest.raises(hssbem.Error) as e:
        hssbem.solve(make(), opts)
    message = str(e.value)
    assert says in message and "\n" not in message and message.strip() == message, message
    assert "PETSc" not in message or "option" in message, message


def test_usable_after_an_error():
    """An error leaves nothing behind: the next solve works (and PETSc's options are its own)."""
    with pytest.raises(hssbem.Error):
        hssbem.solve(problem("cube_dense"), {"ksp_rtoll": 1e-9})
    r = hssbem.solve(problem("cube_dense"), options("cube_dense"))
    assert r.attributes["mat_type"] == "dense"


def test_comm_accepted():
    """An mpi4py communicator: COMM_WORLD, or a duplicate of it, gives the same answer."""
    from mpi4py import MPI
    dup = MPI.COMM_WORLD.Dup()
    try:
        a = hssbem.solve(problem("cube_dense"), options("cube_dense"), comm=dup)
        b = hssbem.solve(problem("cube_dense"), options("cube_dense"), comm=MPI.COMM_WORLD)
        assert_identical(a.fields["displacement"], b.fields["displacement"], "displacement")
        assert a.attributes["ranks"] == COMM.size
    finally:
        dup.Free()
    with pytest.raises(hssbem.Error):
        hssbem.solve(problem("cube_dense"), comm="world")


def test_option_table():
    assert hssbem.option_default("ksp_rtol") > 0
    assert "bem_mat_type" in hssbem.option_help()
    with pytest.raises(hssbem.Error):
        hssbem.option_default("no_such_option")
