/// \file bind.hpp
/// The compiled part of the Python module (_hssbem): a thin client of the session layer
/// (include/hssbem/session/). What the files of python/src/ share: the PETSc environment of a
/// call (its options, PETSc's errors returned instead of printed), the problem as the Python
/// side hands it over (a file or the JSON of a dict, and the mesh's arrays), and the arrays
/// handed back as numpy views of C++ storage.
#pragma once

#include "hssbem/io/hdf5_output.hpp"
#include "hssbem/problem/setup.hpp"
#include "hssbem/session/options.hpp"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <mpi.h>
#include <petscsys.h>

#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace hssbem::py_module {

namespace py = pybind11;

/// An option as the Python side gives it: the name without the dash and its value (none: a flag).
using OptionList = std::vector<std::pair<std::string, std::optional<std::string>>>;

/// For the lifetime of the object: PETSc's errors are returned to the caller instead of printed
/// (a Python user sees one line in hssbem.Error, never PETSc's traceback), and `options` is the
/// options database that every object created meanwhile reads (a database of its own, pushed over
/// the global one: a call reads its options and nothing else). On a communicator of one rank the
/// call can also be interrupted (Ctrl-C): see Interrupted.
class CallEnvironment {
public:
  explicit CallEnvironment(const OptionList &options, MPI_Comm comm = MPI_COMM_NULL);
  ~CallEnvironment();
  CallEnvironment(const CallEnvironment &) = delete;
  CallEnvironment &operator=(const CallEnvironment &) = delete;

private:
  PetscOptions m_options = nullptr;
  bool m_pushed = false, m_quiet = false, m_hooked = false;
};

/// Thrown by the progress hook (core/progress.hpp) that a call on one rank installs, at the
/// engines' checkpoints (a level of the H² compression or factorization, a GMRES iteration, a
/// step of a scene's set-up), when Python has a signal pending (PyErr_CheckSignals(): Ctrl-C):
/// the solve ends through the engines' ordinary error path (PETSc's faces turn it into an error
/// code, RAII frees what was built) and guarded() hands Python its KeyboardInterrupt. Not on
/// several ranks: one rank leaving a collective step would leave the others waiting.
class Interrupted : public std::runtime_error {
public:
  Interrupted() : std::runtime_error("interrupted (a signal, e.g. Ctrl-C)") {}
};

/// The exception Python has pending (KeyboardInterrupt after an interrupted solve), if any.
void throw_if_python_error();

/// The communicator of a call: the Fortran handle of an mpi4py communicator (comm.py2f()), or
/// PETSC_COMM_WORLD when none is given.
MPI_Comm comm_of(const std::optional<long long> &fortran_handle);

/// The problem as the Python side hands it over: a problem file, or the JSON text of a dict in
/// the file's grammar with, when its "mesh" held arrays, the mesh made of them.
struct ProblemInput {
  std::string path;       ///< a problem file; empty: `json`
  std::string json;       ///< the dict as JSON ("mesh" a placeholder when `mesh` is given)
  std::shared_ptr<const SurfaceMesh> mesh;
};

/// The mesh of "mesh": {"vertices": V, "triangles": T}: V an (n, 3) array of real numbers, all
/// finite, T an (m, 3) array of integers (checked: shapes, dtypes, finiteness; then the checks
/// of every mesh, validate_and_orient(), when the problem is set up). Throws std::invalid_argument.
std::shared_ptr<const SurfaceMesh> mesh_of_arrays(const py::object &vertices, const py::object &triangles);

/// The problem set up on every rank of comm (collective: a failure on one rank ends all), with
/// the command line's overrides (-mesh, -o, -E, -nu, -bem_feature_angle) and the interior points
/// checked.
std::shared_ptr<const ProblemSetup> set_up(MPI_Comm comm, const ProblemInput &in, ProblemOverrides overrides);

/// A problem file's "output" path (or -o), checked on rank 0 as the driver does.
void check_output(MPI_Comm comm, const ProblemSetup &s);

/// Numpy views of a vector's storage, without a copy: `owner` keeps it alive.
py::array view_vec3(const std::vector<Vec3> &v, py::handle owner);
py::array view_voigt(const std::vector<Voigt> &v, py::handle owner);
py::array view_doubles(const std::vector<double> &v, py::handle owner);
py::array view_mask(const std::vector<std::array<bool, 3>> &v, py::handle owner);
py::array view_triangles(const std::vector<std::array<int, 3>> &t, py::handle owner);
/// A small array copied (forces, reactions: three numbers).
py::array copy_vec3(const Vec3 &v);

/// The arrays of a result (ResultData) or a frame (FrameData) as dicts named as the result
/// file's datasets.
py::dict fields_of(const ResultData &r, py::handle owner);
py::dict contact_of(const ContactData &c, py::handle owner);

/// petsc4py's C API (PyPetscMat_New, ...), once petsc4py initialised PETSc.
void import_petsc4py_api();

/// Registers the classes of each file in the module.
void bind_solve(py::module_ &m);
void bind_scene(py::module_ &m);
void bind_operator(py::module_ &m);

} // namespace hssbem::py_module

namespace hssbem::py_module {

/// An error of a call, as hssbem.Error: one line, the option at fault named.
class Failure : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
};

/// The one line a C++ exception says to Python (app/main.hpp's message, the option named).
std::string message_of(const std::exception &e);

/// fn() with every C++ exception but Python's own turned into Failure while the call's
/// environment (its options) still stands, so that the message can name the option at fault.
/// When Python has an exception pending (an Interrupted solve's KeyboardInterrupt, whatever the
/// engines made of the Interrupted on its way out), that exception is raised instead.
template <class F>
auto guarded(F &&fn) -> decltype(fn())
{
  try {
    if constexpr (std::is_void_v<decltype(fn())>) {
      fn();
      throw_if_python_error();
    } else {
      auto r = fn();
      throw_if_python_error();
      return r;
    }
  } catch (const py::error_already_set &) {
    throw;
  } catch (const py::builtin_exception &) {
    throw;
  } catch (const Failure &) {
    throw;
  } catch (const std::exception &e) {
    throw_if_python_error();
    throw Failure(message_of(e));
  }
}

} // namespace hssbem::py_module
