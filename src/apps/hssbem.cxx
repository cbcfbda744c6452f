static const char help[] = "hssbem: 3D linear elastostatics by the boundary element method.\n"
                           "Usage: mpirun -n P hssbem -problem FILE.json [-mesh F] [-E x] [-nu x] [-o out.h5] [PETSc options]\n\n";

/* The hssbem driver: the application (app/run.hpp) between PetscInitialize() and PetscFinalize(). */
#include "hssbem/app/petsc_call.hpp"
#include "hssbem/app/run.hpp"
#include "hssbem/petsc/log.h"

#include <exception>

int main(int argc, char **argv)
{
  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  PetscCall(HssbemInitializePackage());
  int status = 0;
  try {
    hssbem::run_driver(PETSC_COMM_WORLD);
  } catch (const hssbem::PetscFailure &e) {
    PetscCall(e.code()); /* PETSc has printed the error: end the traceback here and exit with its code */
  } catch (const std::exception &e) {
    PetscCall(PetscPrintf(PETSC_COMM_WORLD, "hssbem: error: %s\n", e.what()));
    status = 1;
  }
  PetscCall(PetscFinalize());
  return status;
}
