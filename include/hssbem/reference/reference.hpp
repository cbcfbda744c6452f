/// \file reference.hpp
/// A reference factorization: the system A₀ of one boundary-condition pattern S₀ factored once,
/// and what the real-time engines ask of it — scenes (dense_scene.hpp) and contact
/// (contact/contact_engine.hpp) alike.
///
/// With K = [H, −G], A₀ takes per unknown j (3 · node + component) the column H(:, j) where u_j
/// is unknown and −G(:, j) where t_j is unknown; the column S₀ does not use is K₀′(:, j). A
/// known value v_j then enters the right-hand side as −K₀′(:, j) v_j, so the unknowns of any
/// values are x = −Σ_j W(:, j) v_j with W = A₀⁻¹ K₀′ (plus −Σ_n W_p(:, n) p_n for pressure
/// loads, W_p = A₀⁻¹ Gn). Column j of W is the response of every unknown to a unit known value
/// at j: for a traction-known j, the displacement (and the reactions) of a unit traction there.
///
/// What an engine needs is therefore: solves with A₀ (blocked, several right-hand sides at
/// once), the columns W(:, js) for the unknowns it switches or loads, and the free response
/// y = A₀⁻¹ b₀ of the known values. DenseReference is the dense implementation (LU of A₀); a
/// compressed one (the H² factorization in direct mode) implements the same calls, and its
/// columns() is where blocked multi-right-hand-side solves pay.
#pragma once

#include "hssbem/bem/bem_operator.hpp"
#include "hssbem/core/default_init_allocator.hpp"

#include <cstddef>
#include <memory>
#include <unordered_map>
#include <vector>

namespace hssbem {

class ReferenceFactorization {
public:
  virtual ~ReferenceFactorization() = default;

  /// The reference pattern S₀ per unknown (3 · node + component): 1 where u is known (the
  /// unknown is t), 0 where t is known (the unknown is u).
  virtual const std::vector<char> &pattern() const = 0;
  int num_unknowns() const { return static_cast<int>(pattern().size()); }

  /// X ← A₀⁻¹ X for nrhs right-hand sides, column-major with leading dimension num_unknowns().
  virtual void solve(double *X, int nrhs) const = 0;
  /// out = W(:, js) = A₀⁻¹ K₀′(:, js), column-major num_unknowns() × |js| (leading dimension
  /// num_unknowns()): one blocked solve for all of them.
  virtual void columns(const std::vector<int> &js, double *out) const = 0;
  /// y = A₀⁻¹ b for the known values (and pressure loads) of `sel`, whose pattern must be S₀:
  /// the unknowns of that problem. Throws std::invalid_argument for another pattern.
  virtual void free_response(const SystemSelection &sel, std::vector<double> &y) const = 0;
  /// Bytes held.
  virtual std::size_t memory_bytes() const = 0;
  /// False when columns() gives W only to a tolerance (a compressed factorization's solves
  /// alone: H2Reference) while solve() and free_response() are accurate: an engine then corrects
  /// its answer with accurate solves (the contact engine's correction, docs/contact.md).
  virtual bool exact_columns() const { return true; }
};

struct DenseReferenceOptions {
  bool keep_operator = true; ///< keep H and G after the set-up (rhs(), apply(), columns() and free_response() need them)
  bool with_pressure = false; ///< also assemble Gn (pressure loads: pressure_columns(), free responses with pressure)
  /// Per dof node, the body it belongs to (contact/bodies.hpp), or empty: one body. Separate
  /// bodies are separate domains: each collocation row integrates over its own body only (the
  /// other bodies' blocks of H and G are zero, and the rigid-body term sums its own body's
  /// triangles). The whole-mesh operator holds the same equations only in exact arithmetic: its
  /// other-body integrals vanish analytically, but where bodies nearly touch (contact) they are
  /// nearly singular, and their quadrature error moved two Hertz spheres' contact radius by 7 %.
  std::vector<int> node_body;
  /// Keep only K₀′ — the columns of K = [H, −G] that A₀ does not use, all that columns() and
  /// free_response() read — instead of H and G: the rows are assembled straight into A₀ (then
  /// factored in place) and K₀′, so the set-up holds 16 N² bytes, not 24 N². rhs() then takes
  /// the reference pattern only, and apply() and system_matrix() refuse (scenes' refactor and
  /// krylov strategies need H and G). One body only (node_body empty: see CompositeReference).
  bool reference_columns_only = false;
  /// With reference_columns_only: per unknown, 1 where its column of K₀′ is kept (empty: every
  /// one). A column not kept can be neither asked of columns() nor carry a non-zero known value
  /// in free_response() (std::invalid_argument): K₀′ takes 8 N · kept bytes. A contact needs the
  /// candidates' columns and those of the unknowns whose known values are not zero.
  std::vector<char> kept_columns;
};

/// What a dense reference holds once set up: the arrays a saved precomputation keeps
/// (session/precomputation_file.hpp) and gives back to DenseReference(DenseReferenceData).
struct DenseReferenceData {
  std::vector<char> pattern;        ///< the reference pattern, one entry per unknown
  std::vector<double> H, G, Gn;     ///< the operator (keep_operator), column-major; Gn with pressure
  std::vector<double> K;            ///< reference_columns_only: the kept columns of K₀′, column-major
  std::vector<int> kpos;            ///< per unknown: its column in K, or -1 (empty: H and G hold them)
  std::vector<double, DefaultInitAllocator<double>> lu; ///< LU of A₀ (LAPACK getrf), column-major; resize() leaves it unset (a load overwrites it)
  std::vector<int> piv;             ///< its pivots (1-based)
  double scale_t = 1;               ///< ‖H‖_F / ‖G‖_F (operator_scale())
};

/// The dense reference: H and G assembled, A₀ = LU (LAPACK), W's columns by getrs on demand.
/// Memory 8 N² bytes for the LU, plus 16 N² for H and G (keep_operator) or 8 N · kept for K₀′
/// alone (reference_columns_only), and 8 N² / 3 for Gn.
class DenseReference final : public ReferenceFactorization {
public:
  /// Assembles and factors A₀ for `pattern` (one entry per unknown, 1 where u is known). Throws
  /// std::runtime_error when A₀ is singular (a pattern that leaves a body free to move).
  DenseReference(const BemOperator &op, std::vector<char> pattern, const DenseReferenceOptions &options = {});
  /// A reference set up before (data() of one, saved and loaded): no assembly, no factorization.
  /// Throws std::invalid_argument when the arrays do not fit together (sizes, pivots, kept
  /// columns), so that no solve ever reads outside them.
  explicit DenseReference(DenseReferenceData data);
  ~DenseReference() override;
  DenseReference(const DenseReference &) = delete;
  DenseReference &operator=(const DenseReference &) = delete;

  const std::vector<char> &pattern() const override { return m_d.pattern; }
  void solve(double *X, int nrhs) const override;
  void columns(const std::vector<int> &js, double *out) const override;
  void free_response(const SystemSelection &sel, std::vector<double> &y) const override;
  std::size_t memory_bytes() const override;

  /// out = A₀⁻¹ Gn(:, nodes) (N × |nodes|): the responses to unit pressures (with_pressure).
  void pressure_columns(const std::vector<int> &nodes, double *out) const;
  /// b_S = −Σ_j K_S′(:, j) v_j − Σ_n Gn(:, n) p_n for the pattern `pattern` (one char per
  /// unknown, 1 where u is known) and the values of sel (needs the operator).
  void rhs(const SystemSelection &sel, const std::vector<char> &pattern, std::vector<double> &b) const;
  /// y = A_S x (needs the operator).
  void apply(const std::vector<char> &pattern, const double *x, double *y) const;
  /// A_S, column-major N × N, into A (needs the operator).
  void system_matrix(const std::vector<char> &pattern, double *A) const;
  bool has_operator() const { return !m_d.H.empty(); }
  /// What it holds (to save it).
  const DenseReferenceData &data() const { return m_d; }
  /// Frees H, G and Gn (what keep_operator = false does after the set-up).
  void drop_operator();
  /// ‖H‖_F / ‖G‖_F: the scale of −G columns against H columns (the krylov strategy's scaling).
  double operator_scale() const { return m_d.scale_t; }

private:
  void assemble(const BemOperator &op);
  /// Row block r0 .. r0 + rows of H and G (row-major, ld N) into their places: H and G, or A₀ and K₀′.
  void place_rows(int r0, int rows, const double *H, const double *G, double sums[2]);
  void check_options() const;
  /// Column j of K₀′ is at hand (H and G, or kept in K₀′).
  bool has_column(int j) const { return has_operator() || (!m_d.kpos.empty() && m_d.kpos[j] >= 0); }
  /// Separate bodies' rows and columns made independent (DenseReferenceOptions::node_body).
  void separate_bodies(const BemOperator &op);
  void factor();
  /// K₀′(:, j) into col (N entries).
  void reference_column(int j, double *col) const;

  int m_n = 0, m_nodes = 0;
  DenseReferenceOptions m_opt;
  DenseReferenceData m_d;
};

/// Columns W(:, j) of a reference factorization, computed on demand in blocks and kept (a
/// contact's candidates come back frame after frame). Pointers stay valid for the object's life.
///
/// Rows may be kept in another order (`row_order`: the original row at each position): a
/// contact reads the rows of its candidates out of many columns, and with the unknowns in a
/// spatial order those rows lie in a few contiguous runs of each column instead of one cache
/// line each (measured on the 10k organ: see docs/contact.md). Each column is also kept in
/// single precision for products whose result tolerates it (the fields of a frame).
class ReferenceColumns {
public:
  explicit ReferenceColumns(const ReferenceFactorization &reference, std::vector<int> row_order = {});

  /// Makes sure every column of js is here: the missing ones in one blocked columns() call.
  void require(const std::vector<int> &js);
  bool has(int j) const { return m_index.count(j) != 0; }
  /// Column j (N entries, rows in row_order); require() it first (throws std::out_of_range otherwise).
  const double *column(int j) const { return m_index.at(j); }
  /// The same in single precision.
  const float *column_single(int j) const { return m_single.at(j); }
  /// Where original row i sits in a column.
  int position(int i) const { return m_position.empty() ? i : m_position[i]; }
  const std::vector<int> &row_order() const { return m_order; }
  /// W(i, j) for a column held (i an original row).
  double entry(int i, int j) const { return m_index.at(j)[position(i)]; }
  std::size_t size() const { return m_index.size(); }
  std::size_t memory_bytes() const;
  /// Seconds spent computing columns so far.
  double seconds() const { return m_seconds; }
  const ReferenceFactorization &reference() const { return *m_ref; }

  /// The columns held, block by block as require() computed them: each block's unknowns and its
  /// columns (N × |js|, column-major, rows in row_order()) — what a saved precomputation keeps.
  struct Block {
    const std::vector<int> &js;
    const double *data;
  };
  std::vector<Block> blocks() const;
  /// A block computed before (one of blocks(), saved and loaded; rows in this cache's
  /// row_order()), held as if require() had computed it: its single-precision copy is made here
  /// as require() makes it, so the columns are the same to the bit. Throws std::invalid_argument
  /// for an unknown out of range or held already.
  void adopt(std::vector<int> js, std::unique_ptr<double[]> block);

private:
  /// Holds `block` (the columns of js, rows in order) and its single-precision copy.
  void keep(std::vector<int> js, std::unique_ptr<double[]> block);

  const ReferenceFactorization *m_ref;
  std::vector<int> m_order, m_position;
  std::vector<std::unique_ptr<double[]>> m_blocks;
  std::vector<std::unique_ptr<float[]>> m_single_blocks;
  std::vector<std::vector<int>> m_block_columns; ///< per block: its unknowns
  std::size_t m_columns = 0;
  double m_seconds = 0;
  std::unordered_map<int, const double *> m_index;
  std::unordered_map<int, const float *> m_single;
};

} // namespace hssbem
