/// \file composite_reference.hpp
/// The reference factorization (reference.hpp) of a mesh of several bodies: one reference per
/// body, each on that body's own surface and operator.
///
/// Separate bodies are separate domains: a collocation point of one body integrates over its own
/// body's triangles only, so A₀ is block diagonal by body and the bodies meet only through
/// contact. The whole-mesh operator holds the same equations only in exact arithmetic (its
/// other-body integrals vanish analytically but are nearly singular where the bodies nearly
/// touch); DenseReferenceOptions::node_body zeroes them in one dense system of the whole mesh
/// (8 (Σ N_b)² bytes for the LU alone). Here each body b is a mesh of its own (its triangles, its
/// vertices renumbered), with its own discretization, operator and reference — dense or H², as
/// the factory chooses — so no cross-body integral is ever evaluated, the dense memory is
/// Σ 8 N_b², and a body too large for dense memory can take the H² reference. solve(),
/// columns() and free_response() split their vectors by body, call each body's reference and
/// scatter the answers back (a column of W is zero outside its body).
#pragma once

#include "hssbem/bem/bem_operator.hpp"
#include "hssbem/reference/reference.hpp"

#include <functional>
#include <memory>
#include <vector>

namespace hssbem {

/// Makes body `body`'s reference on its own operator, for its pattern (one entry per unknown of
/// the body, 1 where u is known) and `kept` (per unknown of the body: 1 where the caller may ask
/// its column or give it a non-zero known value; a hint a dense reference may use to keep less).
using BodyReferenceFactory =
    std::function<std::unique_ptr<ReferenceFactorization>(const BemOperator &op, std::vector<char> pattern, std::vector<char> kept, int body)>;

class CompositeReference final : public ReferenceFactorization {
public:
  /// `node_body`: the body of every dof node of op's discretization (contact/bodies.hpp,
  /// node_bodies), bodies numbered 0 .. B − 1; `pattern`: one entry per unknown; `kept`: per
  /// unknown, passed on to the factory by body (empty: every unknown). Each body's operator
  /// takes op's material and quadrature options and the discretization's feature angle. Throws
  /// std::invalid_argument for sizes that do not match, std::logic_error if a body's own
  /// discretization does not reproduce the whole mesh's dof nodes.
  CompositeReference(const BemOperator &op, const std::vector<int> &node_body, std::vector<char> pattern, std::vector<char> kept, const BodyReferenceFactory &make);
  ~CompositeReference() override;
  CompositeReference(const CompositeReference &) = delete;
  CompositeReference &operator=(const CompositeReference &) = delete;

  const std::vector<char> &pattern() const override { return m_pattern; }
  void solve(double *X, int nrhs) const override;
  /// W(:, js): each body's columns by its own reference (one blocked call per body and chunk),
  /// zero outside the body.
  void columns(const std::vector<int> &js, double *out) const override;
  void free_response(const SystemSelection &sel, std::vector<double> &y) const override;
  std::size_t memory_bytes() const override;
  bool exact_columns() const override;

  int num_bodies() const { return static_cast<int>(m_parts.size()); }
  const ReferenceFactorization &body_reference(int b) const;
  /// The whole mesh's dof node of each of body b's own dof nodes.
  const std::vector<int> &body_nodes(int b) const;
  /// Seconds each body's set-up took (its operator and reference).
  double body_seconds(int b) const;

private:
  struct Part;
  /// The rows of body b's unknowns out of (or into) a whole-mesh vector.
  void gather(int b, const double *x, double *xb) const;
  void scatter(int b, const double *xb, double *x) const;

  std::vector<char> m_pattern;
  std::vector<int> m_body;  ///< per dof node
  std::vector<int> m_local; ///< per dof node: its index in its body
  std::vector<std::unique_ptr<Part>> m_parts;
};

} // namespace hssbem
