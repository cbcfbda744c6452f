/// \file petsc_call.hpp
/// Moved to session/petsc_call.hpp (the session layer calls PETSc too); kept so that code that
/// includes it still builds.
#pragma once

#include "hssbem/session/petsc_call.hpp"
