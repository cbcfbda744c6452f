/// \file bem_operator.hpp
/// The one primitive: blocks H(I, J), G(I, J) and A(I, J) of the collocation system.
///
/// Rows are collocation points (one per dof node), columns dof nodes; each node has 3 rows and 3
/// columns (components). Somigliana's identity at collocation point x_i reads
///   Σ_j H(i, j) u_j = Σ_j G(i, j) t_j,
/// with G(i, j) = ∫ u*(x_i, y) N_j(y) dΓ and H(i, j) = ∫ p*(x_i, y) (N_j(y) - w_j(x_i)) dΓ, where
/// w_j(x_i) interpolates u at x_i. The free term and the principal value never appear: a rigid
/// translation gives zero traction, so they equal minus the integral of p* over the triangles that
/// do not contain x_i. That sum, D_i = -Σ_{e ∌ x_i} ∫_e p*, is the "rigid-body term" of row i.
#pragma once

#include "hssbem/bem/discretization.hpp"
#include "hssbem/bem/kelvin.hpp"
#include "hssbem/bem/quadrature.hpp"
#include "hssbem/bem/regular_rule.hpp"

#include <memory>
#include <vector>

namespace hssbem {

/// A request for a few entries of H, G and Gn: rows are components of collocation points, columns
/// are kinds of a node's columns (0–2: H's three components, 3–5: G's, 6: Gn's one column). A
/// compression asks for a component or two of many nodes, so only those entries are accumulated
/// from each triangle's integrals. Build with add_row/add_col, then finish().
class EntrySelection {
public:
  /// Output row `out` is component `comp` of node `node`'s collocation point.
  void add_row(int node, int comp, int out) { m_rows.push_back({node, comp, out}); }
  /// Output column `out` is kind `kind` of node `node`.
  void add_col(int node, int kind, int out) { m_cols.push_back({node, kind, out}); }
  /// Group the requests by node (call once, after the last add).
  void finish();

  struct Group {
    std::vector<int> nodes, start, what, out; ///< distinct nodes; CSR: entries start[p] .. start[p + 1] of nodes[p]
  };
  const Group &rows() const { return m_row_groups; }
  const Group &cols() const { return m_col_groups; }

private:
  struct Item {
    int node, what, out;
  };
  static Group group(std::vector<Item> &items);
  std::vector<Item> m_rows, m_cols;
  Group m_row_groups, m_col_groups;
};

class BemOperator {
public:
  /// Scratch space of block evaluations. The operator itself is read-only during fill_hg, so
  /// threads may evaluate blocks concurrently, each with its own workspace.
  class Workspace {
  public:
    explicit Workspace(const BemOperator &op);

  private:
    friend class BemOperator;
    std::vector<int> col_pos;   ///< node -> column position in J, or -1 (kept at -1 between calls)
    std::vector<char> elem_mark; ///< triangle already listed (kept at 0 between calls)
    std::vector<int> elems;      ///< triangles touching the columns
    std::vector<int> elem_pos;   ///< their corners' column positions (col_pos), three per triangle
    std::vector<int> regular;    ///< those a row sees through the 7-point rule
    std::vector<CornerSums> sums; ///< their corner sums
    std::vector<double> acc;      ///< per column node of a selection: its blocks summed over its triangles (per row point)
  };

  BemOperator(const Discretization &disc, const Material &material, const QuadratureOptions &options = {});
  BemOperator(const BemOperator &) = delete;
  BemOperator &operator=(const BemOperator &) = delete;

  const Discretization &discretization() const { return *m_disc; }
  const Material &material() const { return m_material; }
  const QuadratureOptions &quadrature_options() const { return m_quad_options; }
  int num_nodes() const { return m_disc->num_nodes(); }

  /// Rigid-body terms of the given rows by direct summation over all triangles (O(rows · nt)).
  void compute_rigid_body_terms(const std::vector<int> &rows);
  /// Install rigid-body terms computed elsewhere (e.g. by a fast matvec), one per node.
  void set_rigid_body_terms(std::vector<Mat3> terms);
  bool has_rigid_body_term(int row) const;

  /// H(I, J) and G(I, J), row-major with leading dimension ld (>= 3|J|); either may be null.
  /// I and J hold distinct node indices (J holding every node is recognised by its size).
  /// Rows of I need their rigid-body terms (compute_rigid_body_terms) unless J holds every node,
  /// in which case they are summed on the way. This overload uses the operator's own workspace
  /// and is not thread-safe; pass a Workspace per thread for concurrent calls.
  void fill_hg(const std::vector<int> &I, const std::vector<int> &J, double *H, double *G, long ld) const;
  /// As fill_hg, and also Gn(I, J) = Σ_e ∫_e u* N_j n_e (3|I| × |J|, leading dimension ldn): the
  /// response to a unit pressure field N_j carried by flat triangle normals. Thread-safe with
  /// one workspace per thread.
  void fill_hg(const std::vector<int> &I, const std::vector<int> &J, double *H, double *G, long ld, double *Gn, long ldn, Workspace &ws) const;
  /// As fill_hg, but H(I, J) without the rigid-body terms (whatever J holds): the part of H that
  /// quadrature gives. The HSS path compresses this and adds the terms once a fast matvec of it
  /// against the translations has produced them.
  void fill_hg_without_rigid(const std::vector<int> &I, const std::vector<int> &J, double *H, double *G, long ld, double *Gn, long ldn,
                             Workspace &ws) const;
  /// The same integrals with arbitrary points X as rows (points off the surface, e.g. proxy
  /// points around a cluster): 3|X| rows, no rigid-body term. Thread-safe with a workspace.
  void fill_hg_at_points(const std::vector<Vec3> &X, const std::vector<int> &J, double *H, double *G, long ld, double *Gn, long ldn,
                         Workspace &ws) const;
  /// out[r·rs + q·cs] = the requested entries of H, G, Gn (no rigid-body terms): every position
  /// of the selection is written, nothing else. Thread-safe with one workspace per thread.
  void selected(const EntrySelection &sel, double *out, long rs, long cs, Workspace &ws) const;
  /// The same with the points X as rows: out row 3p + c is component c at X[p] (sel's rows unused).
  void selected_at_points(const std::vector<Vec3> &X, const EntrySelection &sel, double *out, long rs, long cs, Workspace &ws) const;
  /// Columns j of the rigid-body term of row i and their weights w_j(x_i) (one column, weight 1,
  /// for a node collocated at its vertex; the corners of its triangle for a moved node): the
  /// term adds w_j(x_i) D_i to block (i, j) of H.
  int rigid_body_columns(int row, int cols[3], double weights[3]) const;

  /// Integrals of triangle t for a collocation point (or an interior point when `row` < 0).
  void element_integrals(const Vec3 &x, int row, int t, ElementIntegrals &out) const;
  const Triangle &triangle(int t) const { return m_tri[t]; }

private:
  bool contains(int row, int t) const;
  /// The three rows of one collocation point in the outputs of fill_hg (null: not wanted).
  struct BlockRows {
    double *H, *G, *Gn;
    long ld, ldn;
    void zero(std::size_t ncols) const;
  };
  void scatter(int t, const ElementIntegrals &ei, const std::vector<int> &col_pos, const BlockRows &out) const;
  void scatter(int t, const CornerSums &cs, const std::vector<int> &col_pos, const BlockRows &out, Mat3 *D) const;
  /// The integrals of every triangle of ws.elems for point x (collocation point of `row`, or
  /// any point when row < 0) added into out; D (if not null) -= those of H over the triangles
  /// that do not contain the point.
  void point_integrals(const Vec3 &x, int row, const BlockRows &out, Workspace &ws, Mat3 *D) const;
  void elements_touching(const std::vector<int> &J, Workspace &ws) const;
  /// ws.elem_pos for ws.elems and ws.col_pos.
  void corner_positions(Workspace &ws) const;
  /// One row point of selected: x (collocation point of `row`, or any point when row < 0)
  /// and its requested components comp[0..nr) going to output rows out_row[0..nr).
  struct RowPoint {
    Vec3 x;
    int row;
    const int *comp, *out_row;
    int nr;
  };
  /// selected for up to RegularRule::lanes row points at once (the triangles' 7-point sums
  /// with the points as SIMD lanes, the other pairs one by one).
  void selected_points(const RowPoint *pts, int np, const EntrySelection::Group &cols, bool gn, double *out, long rs, long cs, Workspace &ws) const;
  enum class Rigid { with, without };
  void fill_rows(const std::vector<int> &I, const std::vector<int> &J, double *H, double *G, long ld, double *Gn, long ldn, Workspace &ws,
                 Rigid rigid) const;
  void add_rigid_body(int row, const Mat3 &D, const std::vector<int> &col_pos, double *Hrow, long ld) const;

  const Discretization *m_disc;
  Material m_material;
  QuadratureOptions m_quad_options;
  ElementQuadrature m_quad;
  std::vector<Triangle> m_tri;
  RegularRule m_regular;
  std::vector<Mat3> m_rigid;
  std::vector<char> m_has_rigid;
  mutable std::unique_ptr<Workspace> m_workspace; ///< for the overload without a workspace
};

/// Which unknown each (node, component) carries, and the known values: the selection E_S of
/// A = K E_S with K = [H, -G].
struct SystemSelection {
  std::vector<std::array<bool, 3>> displacement_known; ///< true: u known, t unknown (column -G)
  std::vector<Vec3> known;                             ///< the known value of each component
  /// Optional, per node: pressure p (NaN if none). Such nodes load each triangle with -p n_e
  /// (its own flat normal) instead of the interpolated nodal traction `known`.
  std::vector<double> pressure;
};

/// A(I, J) (row-major, ld) for a selection: column (j, c) is H(:, j c) where u is unknown and
/// -G(:, j c) where t is unknown. When `rhs` is not null and J holds every node, also
/// rhs(I) = Σ_known -H u + G t. Rigid-body terms as in fill_hg.
void fill_system_block(const BemOperator &op, const SystemSelection &sel, const std::vector<int> &I, const std::vector<int> &J,
                       double *A, long ld, double *rhs);
/// Same, thread-safe with one workspace per thread.
void fill_system_block(const BemOperator &op, const SystemSelection &sel, const std::vector<int> &I, const std::vector<int> &J,
                       double *A, long ld, double *rhs, BemOperator::Workspace &ws);

} // namespace hssbem
