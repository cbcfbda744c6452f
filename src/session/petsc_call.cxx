// PETSc error codes as C++ exceptions (see petsc_call.hpp).
#include "hssbem/session/petsc_call.hpp"
#include "hssbem/petsc/errors.h"

#include <new>

#include <string>

namespace hssbem {

namespace {

/// The message of the last PETSc error, or the generic text of its code.
std::string describe(PetscErrorCode code)
{
  const char *text     = nullptr;
  char       *specific = nullptr;
  if (PetscErrorMessage(code, &text, &specific) != PETSC_SUCCESS) return "PETSc error " + std::to_string(code);
  if (specific && *specific) return specific;
  return text ? text : "PETSc error " + std::to_string(code);
}

} // namespace

PetscFailure::PetscFailure(PetscErrorCode code) : std::runtime_error(describe(code)), m_code(code) {}

void run_collectively(MPI_Comm comm, const std::function<void()> &fn)
{
  PetscErrorCode code = 0;
  std::string    message;
  PetscMPIInt    lowest, nfailed;
  try {
    fn();
  } catch (const std::bad_alloc &) {
    code    = PETSC_ERR_MEM;
    message = "out of memory";
  } catch (const std::exception &e) {
    code    = PETSC_ERR_LIB;
    message = e.what();
  }
  HssbemCallThrow(HssbemAgreeOnError(comm, &code, &message, &lowest, &nfailed));
  if (lowest < 0) return;
  PetscMPIInt size;
  HssbemCallMPIThrow(MPI_Comm_size(comm, &size));
  if (nfailed < size) message += " (on rank " + std::to_string(lowest) + ")"; // as HssbemGuard::Check says it
  throw std::runtime_error(message);
}

EventScope::EventScope(PetscLogEvent event) : m_event(event) { HssbemCallThrow(PetscLogEventBegin(event, 0, 0, 0, 0)); }

EventScope::~EventScope() { PetscCallAbort(PETSC_COMM_SELF, PetscLogEventEnd(m_event, 0, 0, 0, 0)); }

PetscErrorCode mpi_error(int code, int line, const char *func, const char *file)
{
  char msg[MPI_MAX_ERROR_STRING];
  int  len = 0;
  MPI_Error_string(code, msg, &len);
  return PetscError(PETSC_COMM_SELF, line, func, file, PETSC_ERR_MPI, PETSC_ERROR_INITIAL, "MPI error %d %s", code, msg);
}

} // namespace hssbem
