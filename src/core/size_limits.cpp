#include "hssbem/core/size_limits.hpp"

#include <cmath>
#include <cstdio>

namespace hssbem {

namespace {

std::string gigabytes(double bytes)
{
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.3g GB", bytes / 1e9);
  return buf;
}

/// Rows of the largest rank's block of a dense matrix (3 rows per node, nodes split evenly).
long long largest_local_rows(long long unknowns, int ranks)
{
  const long long nodes = unknowns / 3;
  return 3 * ((nodes + ranks - 1) / ranks);
}

/// Memory on one node: its ranks' share of a distributed operator (dense; H², whose parts the
/// ranks hold), or all of a rank-0 one (HSS).
double need_per_node(OperatorType type, long long unknowns, bool single, const MachineLimits &m)
{
  const double total = estimated_bytes(type, unknowns, single);
  if (type == OperatorType::Hss) return total; // lives on rank 0 (not distributed yet)
  return total * m.ranks_per_node / m.ranks;
}

/// Why `type` cannot take the problem (empty: it can), without the suggestion.
std::string why_not(OperatorType type, long long unknowns, bool single, const MachineLimits &m)
{
  if (unknowns > m.index_max) return "has more unknowns than " + std::to_string(m.index_max) + ", the largest index of this PETSc build";
  const long long rows = largest_local_rows(unknowns, m.ranks);
  if (type == OperatorType::Dense && rows * unknowns > m.index_max)
    return "holds " + std::to_string(rows * unknowns) + " entries per rank on " + std::to_string(m.ranks) + " rank(s), more than " + std::to_string(m.index_max) +
           ", the largest index of this PETSc build (32-bit PetscInt)";
  const double need = need_per_node(type, unknowns, single, m);
  if (need > m.node_memory_bytes) return "needs about " + gigabytes(need) + " per node, more than the " + gigabytes(m.node_memory_bytes) + " of memory there";
  return "";
}

/// The path to suggest when `type` cannot take the problem; empty if none can.
std::string alternative(OperatorType type, long long unknowns, const MachineLimits &m)
{
  if (type != OperatorType::H2 && why_not(OperatorType::H2, unknowns, false, m).empty()) return "-bem_mat_type h2";
  if (why_not(OperatorType::H2, unknowns, true, m).empty()) return "-bem_mat_type h2 -mat_h2_single_precision";
  return "";
}

} // namespace

double estimated_bytes(OperatorType type, long long unknowns, bool single_precision)
{
  const double n = static_cast<double>(unknowns);
  switch (type) {
  case OperatorType::Dense: return 16.0 * n * n;
  case OperatorType::H2: return 1.25 * 44e3 * (single_precision ? 1.0 : 1.8) * n;
  case OperatorType::Hss: return 1.25 * 268e6 * std::pow(n / 2994.0, 1.5);
  }
  return 0;
}

std::string size_refusal(OperatorType type, long long unknowns, bool single_precision, const MachineLimits &m)
{
  const std::string why = why_not(type, unknowns, single_precision, m);
  if (why.empty()) return "";
  const std::string alt = alternative(type, unknowns, m);
  return std::string("the ") + operator_type_name(type) + " operator of " + std::to_string(unknowns) + " unknowns " + why +
         (alt.empty() ? "; no operator path fits this machine" : "; use " + alt);
}

} // namespace hssbem
