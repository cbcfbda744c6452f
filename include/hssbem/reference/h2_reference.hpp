/// \file h2_reference.hpp
/// The reference factorization on the H² path (reference.hpp): K = [H, G] compressed as an H²
/// matrix (h2/), A₀ of the reference pattern factored by the H² factorization (h2factor/) at a
/// preconditioner's tolerance, where the dense one would need 8 N² bytes.
///
/// - solve() and free_response() are accurate: GMRES on A₀ (the H² product), right-
///   preconditioned by the factorization, to `rtol` in the true relative residual — a handful of
///   iterations, as the plain H² solve of the driver. The GMRES is the one given (core/krylov.hpp:
///   PETSc's, petsc/krylov.h, with the options prefix -contact_h2_ in the session layer).
/// - columns() are W̃ = F⁻¹ K₀′(:, js): the factorization's solves alone, for a block of
///   right-hand sides at once (the H² product of the unit loads, then
///   H2Factorization::solve_block), accurate to about the factorization's tolerance, not exact:
///   exact_columns() is false, and an engine corrects its answer with accurate solves (the
///   contact engine does: docs/contact.md, "The H² reference").
///
/// One body: the H² matrix couples every collocation point with every triangle, so separate
/// bodies would not be kept apart (their near-contact integrals are nearly singular); several
/// bodies take one H2Reference each in a CompositeReference (composite_reference.hpp).
#pragma once

#include "hssbem/core/krylov.hpp"
#include "hssbem/h2/h2_compression.hpp"
#include "hssbem/h2/h2_system.hpp"
#include "hssbem/h2factor/h2_factorization.hpp"
#include "hssbem/reference/reference.hpp"

#include <memory>

namespace hssbem {

/// The factorization of an H² reference: PC h2's options at -contact_h2_factor_tol.
inline H2FactorOptions h2_reference_factor_options()
{
  H2FactorOptions f;
  f.rel_tol = option_default::contact_h2_factor_tol;
  return f;
}

struct H2ReferenceOptions {
  H2Options compression;  ///< the H² matrix of K (pressure_columns is set from with_pressure)
  H2FactorOptions factor = h2_reference_factor_options(); ///< the factorization of A₀ (a preconditioner's tolerance, -contact_h2_factor_tol)
  double rtol = option_default::contact_h2_rtol; ///< GMRES relative tolerance (true residual) of solve() and free_response()
  int max_it = 300;       ///< GMRES iterations per solve before it is an error (the restart is the Krylov solver's)
  int block = 64;         ///< right-hand sides per blocked solve of columns()
  bool with_pressure = false; ///< also compress Gn (pressure loads in free_response())
};

/// What the set-up and the solves cost.
struct H2ReferenceStats {
  double compress_seconds = 0, factor_seconds = 0, column_seconds = 0, solve_seconds = 0;
  long long columns = 0, solves = 0, iterations = 0; ///< columns made; accurate solves and their GMRES iterations
};

class H2Reference final : public ReferenceFactorization {
public:
  /// Compresses K of `op` and factors A₀ for `pattern` (one entry per unknown, 1 where u is
  /// known); `krylov` makes the accurate solves. Throws H2Breakdown for a singular pivot block (a
  /// pattern that leaves a body free), std::invalid_argument for bad options or no Krylov solver.
  H2Reference(const BemOperator &op, std::vector<char> pattern, const H2ReferenceOptions &options, std::unique_ptr<KrylovSolver> krylov);
  ~H2Reference() override;
  H2Reference(const H2Reference &) = delete;
  H2Reference &operator=(const H2Reference &) = delete;

  const std::vector<char> &pattern() const override { return m_pattern; }
  /// Accurate (GMRES to rtol), column by column. Throws std::runtime_error when GMRES does not
  /// converge within max_it.
  void solve(double *X, int nrhs) const override;
  /// W̃(:, js) = F⁻¹ K₀′(:, js) in blocks of `block` columns, to the factorization's tolerance.
  void columns(const std::vector<int> &js, double *out) const override;
  void free_response(const SystemSelection &sel, std::vector<double> &y) const override;
  std::size_t memory_bytes() const override;
  bool exact_columns() const override { return false; }

  const H2ReferenceStats &stats() const { return m_stats; }
  const H2Matrix &matrix() const { return m_system->matrix(); }
  const H2Factorization &factorization() const { return *m_factor; }

private:
  /// x = A₀⁻¹ b by the Krylov solver, from x = 0 (b and x: mesh order, x may not alias b).
  void accurate_solve(const double *b, double *x) const;
  /// K₀′(:, js[first .. first + count)) in cluster order, column-major (ld 3 × points).
  void reference_columns(const std::vector<int> &js, std::size_t first, int count, double *out) const;

  std::vector<char> m_pattern;
  SystemSelection m_sel; ///< the pattern as a selection (values zero)
  H2ReferenceOptions m_opt;
  std::unique_ptr<H2BemSystem> m_system;
  std::unique_ptr<H2FactorCache> m_cache;
  std::unique_ptr<H2Factorization> m_factor;
  std::unique_ptr<KrylovSolver> m_krylov;
  mutable H2ReferenceStats m_stats;
};

} // namespace hssbem
