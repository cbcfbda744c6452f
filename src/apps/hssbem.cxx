static const char help[] = "hssbem: 3D linear elastostatics by the boundary element method.\n"
                           "Usage: mpirun -n P hssbem -problem FILE.json [-mesh F] [-E x] [-nu x] [-o out.h5] [PETSc options]\n\n";

#include "hssbem/bem/post.hpp"
#include "hssbem/bem/rigid_modes.hpp"
#include "hssbem/io/hdf5_output.hpp"
#include "hssbem/petsc/dense.h"
#include "hssbem/petsc/log.h"
#include "hssbem/app/options.hpp"
#include "hssbem/app/run.hpp"
#include "hssbem/petsc/system.h"
#include "hssbem/problem/setup.hpp"

#include <cstdio>
#include <exception>

/* Build the overrides of the problem file from the command line. */
static hssbem::ProblemOverrides Overrides(const HssbemAppOptions &o)
{
  hssbem::ProblemOverrides ov;
  if (!o.mesh.empty()) ov.mesh = o.mesh;
  if (!o.output.empty()) ov.output = o.output;
  if (o.has_E) ov.E = o.E;
  if (o.has_nu) ov.nu = o.nu;
  ov.feature_angle_deg = o.feature_angle;
  return ov;
}

int main(int argc, char **argv)
{
  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  PetscCall(HssbemInitializePackage());
  int status = 0;
  {
    HssbemAppOptions opts;
    PetscCall(HssbemProcessOptions(PETSC_COMM_WORLD, &opts));
    if (opts.problem.empty()) {
      if (!opts.help) PetscCall(PetscPrintf(PETSC_COMM_WORLD, "hssbem: error: no problem file; give -problem FILE.json (-help lists the options)\n"));
      else { /* list the solver's options too */
        KSP ksp;
        PetscCall(HssbemKSPCreate(PETSC_COMM_WORLD, hssbem::operator_type_name(opts.operator_type), &ksp));
        PetscCall(KSPDestroy(&ksp));
      }
      status = opts.help ? 0 : 1;
    } else {
      try {
        PetscCall(HssbemRun(PETSC_COMM_WORLD, opts.problem, Overrides(opts), opts.quad, hssbem::operator_type_name(opts.operator_type)));
      } catch (const std::exception &e) {
        PetscCall(PetscPrintf(PETSC_COMM_WORLD, "hssbem: error: %s\n", e.what()));
        status = 1;
      }
    }
  }
  PetscCall(PetscFinalize());
  return status;
}
