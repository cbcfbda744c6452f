// Private to app/: what a result file of run.cxx and of scene_run.cxx have in common.
#pragma once

#include "hssbem/io/hdf5_output.hpp"
#include "hssbem/problem/setup.hpp"

#include <petscsys.h>

namespace hssbem {

/// The part of a result file that describes the problem and the run, whatever solved it: the
/// mesh (/mesh/...: vertices, triangles, regions, sharp vertices) and the root attributes of the
/// material, the sizes, the number of ranks (`size`), the versions and the input files.
ResultData result_base(const ProblemSetup &s, PetscMPIInt size);

} // namespace hssbem
