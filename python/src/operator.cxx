// hssbem.operator(): the BEM system A x = b as petsc4py objects, for a KSP of the user's own
// (PC hss and h2 registered by import hssbem). See bind.hpp.
#include "bind.hpp"

#include "hssbem/app/options.hpp"
#include "hssbem/session/petsc_call.hpp"
#include "hssbem/session/static_session.hpp"

#include <petsc4py/petsc4py.h>
#include <pybind11/stl.h>

namespace hssbem::py_module {

namespace {

/// What A's entries (a MatShell's products, PC h2's factorization) are computed from: the
/// problem and its operator, kept alive as long as A is (a container composed with A).
PetscErrorCode DestroyProblem_Private(void *ctx)
{
  delete static_cast<std::shared_ptr<const SessionProblem> *>(ctx);
  return PETSC_SUCCESS;
}

void keep_with(Mat A, const std::shared_ptr<const SessionProblem> &problem)
{
  PetscContainer c;
  HssbemCallThrow(PetscContainerCreate(PetscObjectComm((PetscObject)A), &c));
  HssbemCallThrow(PetscContainerSetPointer(c, new std::shared_ptr<const SessionProblem>(problem)));
  HssbemCallThrow(PetscContainerSetUserDestroy(c, DestroyProblem_Private));
  HssbemCallThrow(PetscObjectCompose((PetscObject)A, "hssbem_problem", (PetscObject)c));
  HssbemCallThrow(PetscContainerDestroy(&c));
}

py::tuple make_operator(const ProblemInput &in, const OptionList &options, std::optional<long long> comm_handle)
{
  const MPI_Comm comm = comm_of(comm_handle);
  const CallEnvironment env(options, comm);
  return guarded([&] {
    const DriverOptions o = read_driver_options(comm);
    const std::shared_ptr<const ProblemSetup> s = set_up(comm, in, o.overrides);
    std::shared_ptr<const SessionProblem> problem;
    run_collectively(comm, [&] { problem = std::make_shared<SessionProblem>(s, o.session.quad); });
    if (problem->job() != JobKind::Static) throw std::invalid_argument(problem->where() + "hssbem.operator takes a static problem (no \"frames\", no \"contact\")");
    StaticSession session(comm, problem, o.session);
    session.assemble();
    check_unused_options(comm, true);
    keep_with(session.matrix(), problem);
    PyObject *A = PyPetscMat_New(session.matrix()), *b = A ? PyPetscVec_New(session.rhs()) : nullptr;
    if (!A || !b) {
      Py_XDECREF(A);
      throw py::error_already_set();
    }
    return py::make_tuple(py::reinterpret_steal<py::object>(A), py::reinterpret_steal<py::object>(b));
  });
}

} // namespace

void import_petsc4py_api()
{
  if (import_petsc4py() < 0) throw py::error_already_set();
}

void bind_operator(py::module_ &m)
{
  m.def("operator", &make_operator, py::arg("problem"), py::arg("options"), py::arg("comm"), "hssbem.operator's compiled part (internal).");
  m.def("option_default", [](const std::string &name) -> py::object {
    const OptionRow *row = find_option(name);
    if (!row) throw Failure("no option named '" + name + "' (hssbem.option_help() lists them)");
    const OptionValue v = OptionValue::default_of(*row);
    switch (row->kind) {
    case OptionKind::Real: return py::float_(v.number);
    case OptionKind::Int: return py::int_(static_cast<long long>(v.number));
    case OptionKind::Bool: return py::bool_(v.number != 0);
    default: return py::str(v.text);
    }
  }, py::arg("name"), "The default of an option of the table of options (name without the dash).");
}

} // namespace hssbem::py_module
