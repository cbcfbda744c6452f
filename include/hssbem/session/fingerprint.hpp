/// \file fingerprint.hpp
/// What a session's precomputation (an operator, a factorization, a reference and its columns)
/// depends on: the mesh, the dof nodes, the material, the reference pattern, the candidates, the
/// options it was made with and the number of ranks. A precomputation made for one fingerprint
/// serves only a problem of the same fingerprint; the values (loads, prescribed displacements,
/// obstacle poses) may differ. A saved precomputation keeps its fingerprint beside it, and a
/// load compares the two (difference()) before it uses anything.
#pragma once

#include "hssbem/core/option_table.hpp"
#include "hssbem/session/problem.hpp"

#include <cstdint>
#include <string>
#include <vector>

namespace hssbem {

struct Fingerprint {
  std::string version;        ///< hssbem's version (a precomputation is read by the version that made it)
  long long vertices = 0, triangles = 0, nodes = 0;
  std::uint64_t mesh = 0;     ///< the vertices' coordinates and the triangles (FNV-1a of their bytes)
  double feature_angle = 0;   ///< the dof nodes follow from the mesh and this angle
  double E = 0, nu = 0;
  long long unknowns = 0;
  std::uint64_t pattern = 0;  ///< the reference pattern: per unknown, whether u is prescribed
  long long candidates = 0;   ///< unknowns whose columns the precomputation may hold (0: every one)
  std::uint64_t candidate_set = 0;
  std::string options;        ///< the options it was made with, "name=value" separated by spaces, by name
  int ranks = 1;              ///< the ranks the precomputation is spread over (a contact's: 1, rank 0's)

  /// The first way in which `stored` (a precomputation's) differs from this one (the problem's),
  /// as one line ("the mesh differs: 13402 vertices in the file, 13398 in the problem"), or empty
  /// when they match.
  std::string difference(const Fingerprint &stored) const;
};

/// The fingerprint of a precomputation for `problem` with the reference pattern `pattern` (one
/// entry per unknown, 1 where u is prescribed; empty: none), the candidate unknowns `candidates`
/// (one entry per unknown, or empty: every one), made with `options` on `ranks` ranks.
Fingerprint fingerprint(const SessionProblem &problem, const std::vector<char> &pattern, const std::vector<char> &candidates, const OptionValues &options, int ranks);

} // namespace hssbem
