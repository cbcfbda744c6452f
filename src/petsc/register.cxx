#include "hssbem/petsc/log.h"

PetscClassId  HSSBEM_CLASSID;
PetscLogEvent BEM_Mesh, BEM_Problem, BEM_RigidBody, BEM_Assembly, BEM_Solve, BEM_Post, BEM_Interior, BEM_Output;

static PetscBool HssbemPackageInitialized = PETSC_FALSE;

/*@C
  HssbemFinalizePackage - Resets the package state so HssbemInitializePackage() can run again.

  Level: developer
@*/
PetscErrorCode HssbemFinalizePackage(void)
{
  PetscFunctionBegin;
  HssbemPackageInitialized = PETSC_FALSE;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/*@C
  HssbemInitializePackage - Registers the class id and the log events of hssbem (one per phase,
  so -log_view shows where the time goes). Called once after PetscInitialize(); later calls do nothing.

  Level: beginner
@*/
PetscErrorCode HssbemInitializePackage(void)
{
  PetscFunctionBegin;
  if (HssbemPackageInitialized) PetscFunctionReturn(PETSC_SUCCESS);
  HssbemPackageInitialized = PETSC_TRUE;
  PetscCall(PetscClassIdRegister("hssbem", &HSSBEM_CLASSID));
  PetscCall(PetscLogEventRegister("BEMMesh", HSSBEM_CLASSID, &BEM_Mesh));
  PetscCall(PetscLogEventRegister("BEMProblem", HSSBEM_CLASSID, &BEM_Problem));
  PetscCall(PetscLogEventRegister("BEMRigidBody", HSSBEM_CLASSID, &BEM_RigidBody));
  PetscCall(PetscLogEventRegister("BEMAssembly", HSSBEM_CLASSID, &BEM_Assembly));
  PetscCall(PetscLogEventRegister("BEMSolve", HSSBEM_CLASSID, &BEM_Solve));
  PetscCall(PetscLogEventRegister("BEMPost", HSSBEM_CLASSID, &BEM_Post));
  PetscCall(PetscLogEventRegister(" BEMInterior", HSSBEM_CLASSID, &BEM_Interior));
  PetscCall(PetscLogEventRegister("BEMOutput", HSSBEM_CLASSID, &BEM_Output));
  PetscCall(PetscRegisterFinalize(HssbemFinalizePackage));
  PetscFunctionReturn(PETSC_SUCCESS);
}
