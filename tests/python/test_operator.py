"""hssbem.operator: the BEM system as petsc4py objects; a petsc4py KSP with PC h2 (registered by
import hssbem) solves it in the command line's iterations."""
import numpy as np
import pytest
from petsc4py import PETSc

import hssbem
from conftest import COMM, attributes, options, problem, reference


def test_petsc4py_ksp_with_pc_h2_takes_the_command_lines_iterations():
    """sphere_l1 with the H² operator: GMRES (the command line's restart and tolerance, right
    preconditioned) with PC h2 on hssbem's Mat converges in the command line's iterations, to a
    true residual below the tolerance."""
    ref = reference("sphere_h2")
    A, b = hssbem.operator(problem("sphere_h2"), options("sphere_h2"))
    assert isinstance(A, PETSc.Mat) and isinstance(b, PETSc.Vec)
    assert A.getSize() == (b.getSize(), b.getSize())
    ksp = PETSc.KSP().create(A.getComm())
    ksp.setOperators(A)
    ksp.setType("gmres")
    ksp.setGMRESRestart(hssbem.option_default("ksp_gmres_restart"))
    ksp.setTolerances(rtol=hssbem.option_default("ksp_rtol"))
    ksp.setPCSide(PETSc.PC.Side.RIGHT)
    ksp.getPC().setType("h2")
    x = b.duplicate()
    ksp.solve(b, x)
    assert ksp.getConvergedReason() > 0
    r = b.duplicate()
    A.mult(x, r)
    r.axpy(-1, b)
    assert r.norm() <= 10 * hssbem.option_default("ksp_rtol") * b.norm()
    assert ksp.getIterationNumber() == attributes(ref)["iterations"]
    assert ksp.getIterationNumber() >= 1 and x.norm() > 0


def test_dense_operator_solves_like_hssbem():
    """The dense operator with PETSc's LU: the unknowns hssbem.solve finds (its displacement)."""
    A, b = hssbem.operator(problem("cube_dense"), options("cube_dense"))
    ksp = PETSc.KSP().create(A.getComm())
    ksp.setOperators(A)
    ksp.setType("gmres")
    ksp.setTolerances(rtol=1e-12)
    ksp.getPC().setType("jacobi")
    x = b.duplicate()
    ksp.solve(b, x)
    assert ksp.getConvergedReason() > 0
    r = b.duplicate()
    A.mult(x, r)
    r.axpy(-1, b)
    assert r.norm() <= 1e-10 * b.norm() and b.norm() > 0


def test_operator_errors():
    with pytest.raises(hssbem.Error) as e:
        hssbem.operator(problem("cardioid_scene"))
    assert "static problem" in str(e.value)
    with pytest.raises(hssbem.Error):
        hssbem.operator(problem("cube_dense"), {"mat_h2_leaf": 3})
