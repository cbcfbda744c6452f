static const char help[] = "hssbem: 3D linear elastostatics by the boundary element method.\n"
                           "Usage: mpirun -n P hssbem -problem FILE.json [-mesh F] [-E x] [-nu x] [-o out.h5] [PETSc options]\n\n";

/* The hssbem driver: the application (app/main.hpp, its one error path, around app/run.hpp)
   between PetscInitialize() and PetscFinalize(). */
#include "hssbem/app/main.hpp"

#include <petscsys.h>

int main(int argc, char **argv)
{
  const bool version = hssbem::take_version_option(&argc, argv);
  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  const int status = hssbem::driver_main(PETSC_COMM_WORLD, version);
  PetscCall(PetscFinalize());
  return status;
}
