#include "hssbem/core/size_limits.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace hssbem {

namespace {

// Fitted constants of the model, see need_per_node() and docs/limits.md.
constexpr double k_hss_digits_power = 1.0;   ///< HSS memory grows as (digits of the tolerance / 8)^p
constexpr double k_h2_fit_tol       = 1e-5;  ///< the H² tolerance the matrix's memory was fitted at (the measured runs')
constexpr double k_h2_factor_fit_tol = 2e-3; ///< PC h2's tolerance its factors' memory was fitted at
constexpr double k_h2_factor_bytes  = 19e3;  ///< PC h2 at k_h2_factor_fit_tol (20k unknowns): factors and working blocks per unknown
constexpr double k_h2_factor_power  = 0.22;  ///< their growth as the tolerance tightens: (k_h2_factor_fit_tol / tol)^p (measured 1.92x at 1e-4)
constexpr double k_h2_double_top    = 16.0;  ///< bytes per entry of a double top at the node's peak (its LU and the rows arriving)
constexpr double k_h2_mixed_top     = 12.0;  ///< of a mixed top on one rank (the double block and the single LU)
constexpr double k_h2_single_top    = 4.0;   ///< of a single-precision top (its LU)
constexpr double k_h2_top_vectors   = 32.0;  ///< bytes per unknown of any top: pivots, offsets, the trial's and the solves' vectors
constexpr double k_h2_top_fill      = 0.8;   ///< the top's size over -pc_h2_top_size (it stops at the first level at or below it: measured about 0.6 and 0.7)
constexpr double k_h2_double_solver = 2.9;   ///< PC h2 beside a double-precision matrix, over beside a single one (measured at 80k)

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

// --- the model (docs/limits.md: the measured peaks it is fitted to) ---------------------------

/// A rank with a tiny problem: MPI, PETSc, OpenBLAS, HDF5 and the driver's code (measured 53 MB).
constexpr double k_process_bytes = 55e6;
/// Per unknown, on every rank (each holds them whole): mesh, dof nodes, the BEM operator's
/// geometry, the selection, the gathered solution and the post-processing (a second rank of the
/// H² run adds 2.5–3.1 kB per unknown beside its 55 MB).
constexpr double k_driver_bytes = 3e3;
/// The operators' and solvers' parts are fitted to within a few percent; this covers the spread
/// of the measurements (and other meshes).
constexpr double k_margin = 1.1;

/// HSS's rank 0 holds the top above the parts besides its share: a quarter of a share (measured
/// on 2 ranks, the largest rank over half of one rank: 1.15 at 3k, 1.19 at 6k, 1.07 at 12k).
constexpr double k_hss_top_share = 0.25;

/// The dense matrix and its LU factor: 16 N² on one rank (PETSc's LU keeps both); on several,
/// the distributed matrix, its ScaLAPACK copy and the redistribution's buffers (measured 27–31 N²
/// in all on 2 ranks).
double dense_bytes(double n, int ranks) { return (ranks > 1 ? 32.0 : 16.0) * n * n; }

/// HSS at 1e-8 with its ULV factors (preonly + PC hss): 144 kB per unknown plus 2.72 kB per
/// unknown^1.5 (fitted to 3k and 12k, 3 % above 6k), times the tolerance's factor.
double hss_bytes(double n, double tol)
{
  const double digits = std::log10(1.0 / std::min(std::max(tol, 1e-14), 0.1));
  return (144e3 * n + 2.72e3 * std::pow(n, 1.5)) * std::pow(digits / 8.0, k_hss_digits_power);
}

/// The H² matrix: 21 kB per unknown with single-precision blocks at tol 1e-5 up to 40 000
/// unknowns (the disk organ's 20.6 kB at 20k, the largest of the sweep), falling as
/// (N / 40 000)^-0.06 beyond (20.1, 19.4 and 18.6 kB at 80k, 150k and 300k against the disk
/// organ's 19.4, 18.9 and 18.4), times (1e-5 / tol)^0.16 (0.61x and 1.45x at 1e-4 and 1e-6 on the
/// 80k disk organ, 0.74x at 1e-4 on a 20k sphere), and 1.8 times that in double precision.
double h2_matrix_bytes(double n, const SizeOptions &o)
{
  const double tol = o.h2_rel_tol > 0 ? o.h2_rel_tol : k_h2_fit_tol;
  return n * 21e3 * std::pow(std::max(n, 4e4) / 4e4, -0.06) * std::pow(k_h2_fit_tol / tol, 0.16) * (o.single_precision ? 1.0 : 1.8);
}

/// PC h2's factors and working blocks beyond the dense top: k_h2_factor_bytes per unknown at its
/// default 2e-3 up to 20 000 unknowns, falling as (N / 20 000)^-0.075 beyond (the measured peaks
/// less the matrix, the driver and the Krylov vectors: 18.2, 16.6 and 15.8 kB at 20k, 80k and
/// 150k), growing as the tolerance tightens; and the Krylov vectors.
double h2_solver_bytes(double n, const SizeOptions &o)
{
  const double tol     = std::min(std::max(o.pc_h2_rel_tol, 1e-12), 0.5);
  const double factors = o.h2_factored ? n * k_h2_factor_bytes * std::pow(std::max(n, 2e4) / 2e4, -0.075) * std::pow(k_h2_factor_fit_tol / tol, k_h2_factor_power) *
                                             (o.single_precision ? 1.0 : k_h2_double_solver)
                                       : 0.0;
  return factors + 8.0 * o.krylov_vectors * n;
}

/// Memory on one node: its ranks' process and driver data, and their shares of the operator
/// (dense, H² and HSS are split over the ranks; HSS's rank 0 also holds the top above the parts,
/// PC h2's rank 0 its dense top unless spread).
double need_per_node(OperatorType type, long long unknowns, const SizeOptions &o, const MachineLimits &m)
{
  const double n = static_cast<double>(unknowns), rpn = m.ranks_per_node, share = rpn / m.ranks;
  const double own = rpn * (k_process_bytes + k_driver_bytes * n);
  switch (type) {
  case OperatorType::Dense: return own + k_margin * dense_bytes(n, m.ranks) * share;
  case OperatorType::Hss: return own + k_margin * hss_bytes(n, o.hss_rel_tol) * (rpn + (m.ranks > 1 ? k_hss_top_share : 0.0)) / m.ranks;
  case OperatorType::H2: return own + k_margin * ((h2_matrix_bytes(n, o) + h2_solver_bytes(n, o)) * share + h2_top_bytes(unknowns, o, m));
  }
  return own;
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
  SizeOptions h = o;
  if (type != OperatorType::H2) h = SizeOptions{};
  std::string opts = type == OperatorType::H2 ? "" : "-bem_mat_type h2";
  if (type != OperatorType::H2 && why_not(OperatorType::H2, unknowns, h, m).empty()) return opts;
  const auto add = [&](const char *opt) { opts += opts.empty() ? opt : std::string(" ") + opt; };
  if (!h.single_precision) {
    h.single_precision = true; // the remedy suggested, not an option's default
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

double estimated_bytes(OperatorType type, long long unknowns, const SizeOptions &o) { return need_per_node(type, unknowns, o, MachineLimits{}); }

double node_bytes(OperatorType type, long long unknowns, const SizeOptions &o, const MachineLimits &m) { return need_per_node(type, unknowns, o, m); }

bool h2_single_panels(double rel_tol, int single_panels) { return single_panels < 0 ? rel_tol >= k_h2_single_panel_tol : single_panels == 1; }

H2TopKind h2_top_kind(long long top_unknowns, bool single_panels, long long single_top_from, bool spread_top, int ranks)
{
  if (single_top_from <= 0 || top_unknowns < single_top_from) return H2TopKind::Double;
  if (!single_panels) return H2TopKind::Mixed;
  return spread_top && ranks > 1 ? H2TopKind::Spread : H2TopKind::Single;
}

double h2_top_bytes(H2TopKind kind, long long top_unknowns, const MachineLimits &m)
{
  const double n = static_cast<double>(top_unknowns), n2 = n * n, vectors = k_h2_top_vectors * n;
  switch (kind) {
  case H2TopKind::Double: return k_h2_double_top * n2 + vectors;
  case H2TopKind::Mixed: return (m.ranks > 1 ? k_h2_double_top : k_h2_mixed_top) * n2 + vectors;
  case H2TopKind::Single: return k_h2_single_top * n2 + vectors;
  case H2TopKind::Spread: return (k_h2_single_top * n2 + vectors) * m.ranks_per_node / m.ranks;
  }
  return 0.0;
}

double h2_top_bytes(long long unknowns, const SizeOptions &o, const MachineLimits &m)
{
  if (!o.h2_factored) return 0.0;
  const auto top = static_cast<long long>(k_h2_top_fill * static_cast<double>(std::min(std::max(o.pc_h2_top_size, 0LL), unknowns)));
  return h2_top_bytes(h2_top_kind(top, h2_single_panels(o.pc_h2_rel_tol, -1), o.pc_h2_mixed_top, o.pc_h2_spread_top, m.ranks), top, m);
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
