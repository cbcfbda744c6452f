/* PETSc's GMRES behind hssbem::KrylovSolver (core/krylov.hpp), for the engines that take one: a
   scene's krylov strategy and the H² reference's accurate solves. On one rank, the operator as a
   MatShell and the preconditioner as a PCShell applied on the right (the tolerance bounds the
   true residual), started from the given guess; a KSP of its own with the options prefix given
   (its options: -<prefix>ksp_monitor, -<prefix>ksp_gmres_restart, ...). */
#pragma once

#include "hssbem/petsc/compat.h"
#include "hssbem/core/krylov.hpp"

#include <memory>

/* The GMRES restart of a scene's krylov strategy (-scene_ksp_gmres_restart overrides it). */
#define HSSBEM_SCENE_KRYLOV_RESTART 100

/* A GMRES-backed KrylovSolver with options prefix `prefix` (e.g. "scene_") and restart
   `restart`; `what` names the solve in its errors ("scene frame", "H2 reference"). Divergence
   throws std::runtime_error naming the reason. */
std::unique_ptr<hssbem::KrylovSolver> HssbemKrylovCreate(const char *prefix, int restart, const char *what);

/* A scene's: HssbemKrylovCreate("scene_", HSSBEM_SCENE_KRYLOV_RESTART, "scene frame"). */
std::unique_ptr<hssbem::KrylovSolver> HssbemSceneKrylovCreate(void);

/* The GMRES restart of an H² reference's accurate solves (-contact_h2_ksp_gmres_restart overrides it). */
#define HSSBEM_H2_REFERENCE_KRYLOV_RESTART 60

/* An H² reference's (reference/h2_reference.hpp): HssbemKrylovCreate("contact_h2_",
   HSSBEM_H2_REFERENCE_KRYLOV_RESTART, "H2 reference"). */
std::unique_ptr<hssbem::KrylovSolver> HssbemH2ReferenceKrylovCreate(void);
