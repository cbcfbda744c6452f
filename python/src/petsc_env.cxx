// The PETSc environment of a call from Python (see bind.hpp).
#include "bind.hpp"

#include "hssbem/core/progress.hpp"
#include "hssbem/session/petsc_call.hpp"

namespace hssbem::py_module {

namespace {

ProgressHook g_outer_hook = nullptr; ///< the hook installed before the call (-hssbem_progress)
bool         g_interrupted = false;  ///< a signal stopped this call: every later checkpoint throws

/// The progress hook of a call on one rank: the outer hook's report, then Python's signal
/// handlers (with the GIL, which the call holds); a pending KeyboardInterrupt stays set for
/// guarded() to raise. A phase's end (done = 1) comes from a destructor: never thrown there.
void interrupt_hook(const char *phase, double done, double seconds)
{
  if (g_outer_hook) g_outer_hook(phase, done, seconds);
  if (done >= 1 || !PyGILState_Check()) return;
  if (!g_interrupted && PyErr_CheckSignals() == 0) return;
  g_interrupted = true;
  throw Interrupted();
}

bool one_rank(MPI_Comm comm)
{
  int size = 0;
  return comm != MPI_COMM_NULL && MPI_Comm_size(comm, &size) == MPI_SUCCESS && size == 1;
}

} // namespace

void throw_if_python_error()
{
  if (PyErr_Occurred()) throw py::error_already_set();
}

CallEnvironment::CallEnvironment(const OptionList &options, MPI_Comm comm)
{
  HssbemCallThrow(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
  m_quiet = true;
  try {
    HssbemCallThrow(PetscOptionsCreate(&m_options));
    for (const auto &[name, value] : options) HssbemCallThrow(PetscOptionsSetValue(m_options, ("-" + name).c_str(), value ? value->c_str() : NULL));
    HssbemCallThrow(PetscOptionsPush(m_options));
    m_pushed = true;
  } catch (...) {
    if (m_options) (void)PetscOptionsDestroy(&m_options);
    (void)PetscPopErrorHandler();
    throw;
  }
  if (one_rank(comm) && progress_hook() != interrupt_hook) {
    g_outer_hook = progress_hook();
    g_interrupted = false;
    set_progress_hook(interrupt_hook);
    m_hooked = true;
  }
}

CallEnvironment::~CallEnvironment()
{
  if (m_hooked) {
    set_progress_hook(g_outer_hook);
    g_outer_hook = nullptr;
    g_interrupted = false;
  }
  if (m_pushed) (void)PetscOptionsPop();
  if (m_options) (void)PetscOptionsDestroy(&m_options);
  if (m_quiet) (void)PetscPopErrorHandler();
}

MPI_Comm comm_of(const std::optional<long long> &fortran_handle)
{
  if (!fortran_handle) return PETSC_COMM_WORLD;
  const MPI_Comm comm = MPI_Comm_f2c(static_cast<MPI_Fint>(*fortran_handle));
  if (comm == MPI_COMM_NULL) throw std::invalid_argument("comm: MPI_COMM_NULL is no communicator to solve on");
  return comm;
}

} // namespace hssbem::py_module
