/* Moved to petsc/krylov.h (the H² reference takes PETSc's GMRES too); kept so that code that
   includes it still builds. */
#pragma once

#include "hssbem/petsc/krylov.h"
