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

/// What the node of rank 0 of a distributed HSS matrix needs beyond its ranks' even shares, as a
/// fraction of a share: the top above the parts (generators and the root block's factors), and
/// what every rank holds whole (mesh, operator, skeleton lists). Measured with bench_hss_mpi on 2
/// ranks, peak resident memory over half that of one rank: rank 0 1.23 (disk_organ_4k) and 1.22
/// (sphere_l2) at 1e-6, rank 1 1.18 and 1.16; the estimate's own 25 % margin covers the others.
constexpr double k_hss_top_share = 0.25;

/// Memory on one node: its ranks' share of a distributed operator (dense; H² and HSS, whose parts
/// the ranks hold; HSS's rank 0 also holds the top above the parts).
double need_per_node(OperatorType type, long long unknowns, const SizeOptions &o, const MachineLimits &m)
{
  const double total = estimated_bytes(type, unknowns, o);
  if (type == OperatorType::Hss && m.ranks > 1) return total * (m.ranks_per_node + k_hss_top_share) / m.ranks;
  return total * m.ranks_per_node / m.ranks;
}

/// Why `type` cannot take the problem (empty: it can), without the suggestion.
std::string why_not(OperatorType type, long long unknowns, const SizeOptions &o, const MachineLimits &m)
{
  if (unknowns > m.index_max) return "has more unknowns than " + std::to_string(m.index_max) + ", the largest index of this PETSc build";
  const long long rows = largest_local_rows(unknowns, m.ranks);
  if (type == OperatorType::Dense && rows * unknowns > m.index_max)
    return "holds " + std::to_string(rows * unknowns) + " entries per rank on " + std::to_string(m.ranks) + " rank(s), more than " + std::to_string(m.index_max) +
           ", the largest index of this PETSc build (32-bit PetscInt)";
  const double need = need_per_node(type, unknowns, o, m);
  if (need > m.node_memory_bytes) return "needs about " + gigabytes(need) + " per node, more than the " + gigabytes(m.node_memory_bytes) + " of memory there";
  return "";
}

/// The options to suggest when `type` cannot take the problem with `o`; empty if none can. In
/// order: H² as asked, then each of single precision, Jacobi instead of PC h2 and tolerance 1e-4
/// added, as long as it is a change.
std::string alternative(OperatorType type, long long unknowns, const SizeOptions &o, const MachineLimits &m)
{
  // Another operator: H² at the driver's defaults (single precision, 1e-5, PC h2 on any number of
  // ranks, distributed like the matrix).
  SizeOptions h = type == OperatorType::H2 ? o : SizeOptions{true, 1e-5, true};
  std::string opts = type == OperatorType::H2 ? "" : "-bem_mat_type h2";
  if (type != OperatorType::H2 && why_not(OperatorType::H2, unknowns, h, m).empty()) return opts;
  const auto add = [&](const char *opt) { opts += opts.empty() ? opt : std::string(" ") + opt; };
  if (!h.single_precision) {
    h.single_precision = true;
    add("-mat_h2_single_precision");
    if (why_not(OperatorType::H2, unknowns, h, m).empty()) return opts;
  }
  if (h.h2_factored) {
    h.h2_factored = false;
    add("-pc_type jacobi");
    if (why_not(OperatorType::H2, unknowns, h, m).empty()) return opts;
  }
  if (h.h2_rel_tol < 1e-4) {
    h.h2_rel_tol = 1e-4;
    add("-mat_h2_rel_tol 1e-4");
    if (why_not(OperatorType::H2, unknowns, h, m).empty()) return opts;
  }
  return "";
}

} // namespace

double estimated_bytes(OperatorType type, long long unknowns, const SizeOptions &o)
{
  const double n = static_cast<double>(unknowns);
  switch (type) {
  case OperatorType::Dense: return 16.0 * n * n;
  case OperatorType::H2: {
    const double tol = o.h2_rel_tol > 0 ? o.h2_rel_tol : 1e-5;
    const double matrix = 23.8e3 * std::pow(std::max(n, 4e4) / 4e4, -0.06) * std::pow(1e-5 / tol, 0.135) * (o.single_precision ? 1.0 : 1.8);
    return 1.1 * n * (matrix + (o.h2_factored ? 40e3 : 0.0));
  }
  case OperatorType::Hss: return 1.25 * 268e6 * std::pow(n / 2994.0, 1.5);
  }
  return 0;
}

std::string size_refusal(OperatorType type, long long unknowns, const SizeOptions &o, const MachineLimits &m)
{
  const std::string why = why_not(type, unknowns, o, m);
  if (why.empty()) return "";
  const std::string alt = alternative(type, unknowns, o, m);
  return std::string("the ") + operator_type_name(type) + " operator of " + std::to_string(unknowns) + " unknowns " + why +
         (alt.empty() ? "; no operator path fits this machine" : "; use " + alt);
}

} // namespace hssbem
