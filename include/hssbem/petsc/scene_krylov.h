/* The Krylov solver of a scene's krylov strategy (hssbem::KrylovSolver, scene/dense_scene.hpp):
   PETSc's GMRES on one rank with the frame's operator as a MatShell and the last factorization as
   a PCShell, right-preconditioned (the tolerance bounds the true residual), started from the
   given guess. Options under the prefix -scene_ (e.g. -scene_ksp_monitor, -scene_ksp_gmres_restart). */
#pragma once

#include "hssbem/petsc/compat.h"
#include "hssbem/scene/dense_scene.hpp"

#include <memory>

/* A new GMRES-backed KrylovSolver; divergence throws std::runtime_error naming the reason. */
std::unique_ptr<hssbem::KrylovSolver> HssbemSceneKrylovCreate(void);
