/// \file hdf5_output.hpp
/// Result files: HDF5 with a ParaView-readable XDMF sidecar, written atomically.
#pragma once

#include "hssbem/core/geometry.hpp"

#include <array>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace hssbem {

class OutputError : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
};

/// Everything a result file holds, all arrays in mesh vertex order. Serial: the caller gathers.
struct ResultData {
  std::vector<Vec3> vertices;
  std::vector<std::array<int, 3>> triangles;
  std::vector<int> triangle_region;                 ///< /mesh/triangle_region
  std::vector<Vec3> displacement;                   ///< /fields/displacement
  std::vector<Vec3> traction;                       ///< /fields/traction (mean over double nodes)
  std::vector<std::array<Vec3, 3>> traction_corner; ///< /fields/traction_corner (nt x 3 x 3)
  std::vector<std::array<bool, 3>> displacement_prescribed; ///< /bc/displacement_prescribed (0/1)
  std::vector<int> sharp_vertex;                    ///< /mesh/sharp_vertex (0/1): double nodes
  std::map<std::string, Vec3> reactions;            ///< /reactions/<region>: integral of traction
  std::vector<Vec3> interior_points;                ///< /interior/points
  std::vector<Vec3> interior_displacement;          ///< /interior/displacement
  std::map<std::string, double> attributes_real;    ///< root attributes (E, nu, residual, ...)
  std::map<std::string, long long> attributes_int;  ///< root attributes (iterations, ranks, ...)
  std::map<std::string, std::string> attributes_str;///< root attributes (solver, version, ...)
  std::map<std::string, double> timings;            ///< /timings attributes, seconds per phase
};

/// Check that `path` can be written (directory exists and is writable) before any work is done.
/// Also refused: a path that is a directory, or whose sidecar name is one; a `.xdmf` path (it
/// would be its own sidecar); a file name containing ':' (XDMF cannot refer to it).
/// Throws OutputError "cannot write output '<path>': <reason>".
void check_output_path(const std::string &path);

/// Write `path` (HDF5) and `path` with extension .xdmf beside it. Both are written under temporary
/// names (`<name>.tmp.<pid>`) and renamed into place together when complete: the earlier pair is
/// replaced whole or not at all (a failed second rename puts the first back), a crash never
/// leaves a file that looks complete, and SIGINT/SIGTERM/SIGHUP during the write remove the
/// temporary files before the signal takes its course.
/// Layout: /mesh/{vertices, triangles, triangle_region, sharp_vertex}, /fields/{displacement,
/// traction, traction_corner}, /bc/displacement_prescribed, /reactions/<region>,
/// /interior/{points, displacement}, root attributes, /timings attributes; empty optional
/// arrays are skipped. Arrays that are not empty must have one entry per vertex (triangle).
/// Throws OutputError; on error no temporary file is left and an existing result is untouched.
void write_result(const std::string &path, const ResultData &data);

} // namespace hssbem
