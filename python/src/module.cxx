// The compiled part of the Python module hssbem: _hssbem (see bind.hpp and python/hssbem/).
#include "bind.hpp"

#include "hssbem/app/main.hpp"
#include "hssbem/core/option_table.hpp"
#include "hssbem/petsc/log.h"
#include "hssbem/session/petsc_call.hpp"

#include <new>

namespace hssbem::py_module {

std::string message_of(const std::exception &e)
{
  if (dynamic_cast<const std::bad_alloc *>(&e)) return "out of memory (an allocation failed; a smaller problem, more memory, or bem_mat_type h2 may help)";
  std::string m = name_the_option(e.what());
  const std::string help = "run with -help to list the options";
  if (const auto at = m.find(help); at != std::string::npos) m.replace(at, help.size(), "hssbem.option_help() lists them");
  while (!m.empty() && (m.back() == '\n' || m.back() == ' ')) m.pop_back();
  for (char &c : m)
    if (c == '\n') c = ' ';
  return m;
}

namespace {

/// After petsc4py initialised PETSc: its C API, and hssbem's package (PC hss and h2, the log
/// events).
void initialize()
{
  PetscBool up = PETSC_FALSE;
  if (PetscInitialized(&up) != PETSC_SUCCESS || !up) throw Failure("PETSc is not initialised (import hssbem initialises it through petsc4py)");
  import_petsc4py_api();
  HssbemCallThrow(HssbemInitializePackage());
}

} // namespace

} // namespace hssbem::py_module

namespace py = pybind11;

PYBIND11_MODULE(_hssbem, m)
{
  namespace hp = hssbem::py_module;
  m.doc() = "The compiled part of hssbem (internal): use the package hssbem.";
  static py::exception<hp::Failure> error(m, "Error", PyExc_RuntimeError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const py::error_already_set &) {
      throw;
    } catch (const py::builtin_exception &) {
      throw;
    } catch (const std::exception &e) {
      PyErr_SetString(error.ptr(), hp::message_of(e).c_str());
    }
  });
  m.def("_initialize", &hp::initialize);
  m.def("option_help", [] { return hssbem::option_help(hssbem::kEvery); }, "The options of every job, from the table of options.");
  m.attr("__version__") = HSSBEM_PY_VERSION;
  hp::bind_solve(m);
  hp::bind_scene(m);
  hp::bind_operator(m);
}
