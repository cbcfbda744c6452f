/// \file petsc_call.hpp
/// The one place where the layers above the PETSc face (session/, app/) turn a PETSc error code
/// into a C++ exception (the other direction of PetscCallCXX). They throw like every C++ layer;
/// the PETSc face returns PetscErrorCode. Every PETSc call in session/ and app/ goes through
/// HssbemCallThrow (MPI calls through HssbemCallMPIThrow), the way PETSc code goes through
/// PetscCall.
#pragma once

#include "hssbem/petsc/compat.h"

#include <petscsys.h>

#include <functional>
#include <stdexcept>

namespace hssbem {

/// A PETSc call failed. code() is the PetscErrorCode, what() the message of the error (PETSc
/// prints nothing itself while the driver's error path, app/main.hpp, is in place).
class PetscFailure : public std::runtime_error {
public:
  explicit PetscFailure(PetscErrorCode code);
  PetscErrorCode code() const { return m_code; }

private:
  PetscErrorCode m_code;
};

/// Run fn on this rank of comm and agree with the other ranks (collective): if fn threw on any
/// rank, every rank throws std::runtime_error with the message of the lowest failing rank ("out
/// of memory" for std::bad_alloc), followed by " (on rank r)" when some ranks did not fail, so
/// that a failure met by some ranks only (a file system that differs between nodes, rank-0 work
/// such as the output) ends every rank the same way instead of leaving some waiting.
void run_collectively(MPI_Comm comm, const std::function<void()> &fn);

/// A log event open for the lifetime of the object: begun on construction (throws PetscFailure
/// when PETSc refuses), ended on destruction, on the way out of an exception too.
class EventScope {
public:
  explicit EventScope(PetscLogEvent event);
  ~EventScope();
  EventScope(const EventScope &)            = delete;
  EventScope &operator=(const EventScope &) = delete;

private:
  PetscLogEvent m_event;
};

/// PETSC_ERR_MPI, with the message PetscCallMPI() gives, for a failed MPI call (code != MPI_SUCCESS).
PetscErrorCode mpi_error(int code, int line, const char *func, const char *file);

} // namespace hssbem

/// HssbemCallThrow(expr): PetscCall() for a function that throws instead of returning an error
/// code. On failure it adds this frame to PETSc's traceback and throws hssbem::PetscFailure.
#define HssbemCallThrow(...) \
  do { \
    const PetscErrorCode ierr_hssbem_ = __VA_ARGS__; \
    if (PetscUnlikely(ierr_hssbem_ != PETSC_SUCCESS)) \
      throw hssbem::PetscFailure(PetscError(PETSC_COMM_SELF, __LINE__, PETSC_FUNCTION_NAME, __FILE__, ierr_hssbem_, PETSC_ERROR_REPEAT, " ")); \
  } while (0)

/// HssbemCallMPIThrow(expr): the same for an MPI call, as PetscCallMPI() is to PetscCall().
#define HssbemCallMPIThrow(...) \
  do { \
    const int mpierr_hssbem_ = __VA_ARGS__; \
    if (PetscUnlikely(mpierr_hssbem_ != MPI_SUCCESS)) throw hssbem::PetscFailure(hssbem::mpi_error(mpierr_hssbem_, __LINE__, PETSC_FUNCTION_NAME, __FILE__)); \
  } while (0)
