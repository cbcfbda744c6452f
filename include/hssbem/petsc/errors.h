/* Errors that some ranks meet and others do not: the agreement that makes them collective, so
   that an error always ends every rank the same way (see HssbemGuard in src/petsc/ and the
   driver's error path in app/). */
#pragma once

#include "hssbem/petsc/compat.h"

#include <petscsys.h>

#include <string>

/* Collective on comm: each rank says whether it failed (code != 0) and why; on return, lowest is
   the lowest failing rank (-1: none failed), nfailed how many failed, and code and message are
   that rank's, on every rank. */
PetscErrorCode HssbemAgreeOnError(MPI_Comm comm, PetscErrorCode *code, std::string *message, PetscMPIInt *lowest, PetscMPIInt *nfailed);
