/// \file capacitance.hpp
/// Solves with a principal submatrix C = W(J, J) of a fixed dense matrix W while the index set J
/// gains and loses indices: the capacitance matrix of a Woodbury update.
///
/// A scene's reference factorization turns every boundary-condition pattern into "the reference
/// plus |J| switched columns", and the solve needs C⁻¹ for the switched set J (see
/// dense_scene.hpp). A moving contact changes J by a few indices per frame; rebuilding C⁻¹ costs
/// 8/3 |J|³ flops, while removing r indices and adding a (block inverse by Schur complements)
/// costs about 2|J|²r + 6|J|²a.
///
/// Precision. C itself is kept explicitly in double. Its inverse is kept in double, or — for
/// large sets, where the updates' GEMMs dominate a frame — in single precision (twice the GEMM
/// rate, half the memory traffic), and then every solve is refined in double against C
/// (s ← s + C⁻¹(r − C s)) until ‖r − C s‖ ≤ 1e-10 ‖r‖ (k_refine_tol). A scene's unknowns then
/// differ from the exact Woodbury answer by about that (its switched unknowns are s, the others
/// −W(:, J) s = −W(:, J) C⁻¹ r, a bounded map of the residual), two orders below the rounding of
/// the single-precision W(:, J) that goes with a single-precision inverse (dense_scene.hpp; the
/// contact engine keeps its inverse in double). The last step's residual is not computed when
/// the contraction measured so far puts it 10x below the tolerance (a pass over C in double is
/// the dearest part of a solve). When it stops contracting (rounding accumulated over many
/// updates, or an ill-conditioned C), solve() says so and the owner rebuilds (in double if that
/// was single already).
///
/// Storage. C and its inverse live in square arrays with room to spare, one slot per index: a
/// dropped index leaves its slot empty (its row and column zero in both), an added one takes an
/// empty slot or a new one at the end, so an update writes in place and allocates nothing of
/// size |J|². Empty slots are squeezed out once they are more than 1/8 of the slots. (On the
/// 10k organ with 20 % in contact, |J| = 3 015 and ~200 indices changing per frame, this took a
/// pattern-changing frame from 120 to 116 ms; splitting the tall products C⁻¹B by row blocks in
/// gemm_over_threads took it to 92 ms.)
#pragma once

#include <climits>
#include <cstddef>
#include <memory>
#include <vector>

namespace hssbem {

/// The entries of the fixed n×n matrix whose principal submatrices a CapacitanceInverse inverts,
/// when they are computed rather than stored (a contact's compliance, contact/). Entries are read
/// only for indices being added (rebuild(), update()'s `add`); an entry may change while neither
/// of its indices is in the set.
class MatrixEntries {
public:
  virtual ~MatrixEntries() = default;
  /// out[p + q ld] = W(rows[p], cols[q]).
  virtual void block(const std::vector<int> &rows, const std::vector<int> &cols, double *out, std::size_t ld) const = 0;
};

/// The relative residual a single-precision inverse's solves are refined to.
constexpr double k_refine_tol = 1e-10;

/// Entries of a stored column-major matrix with n rows: W(i, j) at W[i + column(j) · n], where
/// column(j) = j, or (*column)[j] for a matrix that keeps some of its columns (the map must
/// outlive this object and give every index asked for).
class StoredColumns final : public MatrixEntries {
public:
  StoredColumns(const double *W, int n, const std::vector<int> *column = nullptr) : m_W(W), m_n(n), m_column(column) {}
  void block(const std::vector<int> &rows, const std::vector<int> &cols, double *out, std::size_t ld) const override;

private:
  const double *m_W;
  int m_n;
  const std::vector<int> *m_column;
};

class CapacitanceInverse {
public:
  /// W is n×n, column-major with leading dimension n; it must outlive this object and not change.
  /// Rebuilds keep the inverse in single precision for sets of at least `single_from` indices
  /// (INT_MAX: always double).
  CapacitanceInverse(const double *W, int n, int single_from = INT_MAX);
  /// The same with W's entries from `entries` (shared: copies of this object read the same).
  CapacitanceInverse(std::shared_ptr<const MatrixEntries> entries, int n, int single_from = INT_MAX);

  /// C⁻¹ for the index set J from scratch (LU of W(J, J), then its inverse). Throws
  /// std::runtime_error when W(J, J) is singular. force_double: keep the inverse in double.
  void rebuild(const std::vector<int> &J, bool force_double = false);
  /// Remove the indices `drop` (each in the set) and add `add` (none in it), in that order.
  /// Throws std::runtime_error when a Schur complement is singular (the caller then rebuilds).
  void update(const std::vector<int> &drop, const std::vector<int> &add);

  /// The current index set, in the order of C's rows and columns (the order of the positions
  /// that solve() and inverse_entry() use; an update may reorder it).
  const std::vector<int> &indices() const { return m_J; }
  /// Position of index j in indices(), or -1.
  int position(int j) const { return m_pos[j]; }
  int size() const { return static_cast<int>(m_J.size()); }
  /// Slots in use (indices plus empty slots) and the arrays' leading dimension (tests, cost model).
  int slots() const { return m_k; }
  int capacity() const { return m_ld; }
  bool single() const { return m_single; }
  /// Per slot (below slots()): the index it holds, or -1 when empty. Slots keep their index
  /// through updates and growth; a rebuild or a squeeze renumbers them.
  const std::vector<int> &slot_indices() const { return m_slot_index; }
  /// Per position of indices(): its slot.
  const std::vector<int> &position_slots() const { return m_pos_slot; }
  /// Refinement steps of the last solve() (1 in double: the product with the inverse).
  int last_iterations() const { return m_last_iterations; }

  /// s = C⁻¹ r for r of length size(); in single precision refined to ‖r − C s‖ ≤ k_refine_tol ‖r‖.
  /// Returns false when the refinement stopped contracting (s is then the best iterate): rebuild.
  bool solve(const double *r, double *s) const;
  /// Entry (p, q) of the current inverse (tests).
  double inverse_entry(int p, int q) const;

  /// Flops of rebuild(J) for |J| = k, and of update() dropping r and adding a indices from |J| = k.
  static double rebuild_flops(double k) { return 8.0 / 3.0 * k * k * k; }
  static double update_flops(double k, double r, double a);

private:
  /// The refinement of a single-precision solve (by slots); false when it stops contracting.
  bool refine(const std::vector<double> &r, std::vector<double> &s) const;
  void drop_indices(const std::vector<int> &drop);
  void add_indices(const std::vector<int> &add);
  /// C's rows and columns of the new slots A (holding `add`), idx the index of every slot (-1: empty).
  void fill_new_entries(const std::vector<int> &idx, const std::vector<int> &A, const std::vector<int> &add);
  /// Room for `slots` slots (grows the arrays, keeping their contents).
  void reserve(int slots);
  /// Move the used slots to the front, in order, and forget the empty ones.
  void squeeze();
  /// m_J and m_pos from the slots.
  void refresh_view();
  static std::vector<int> slots_upto(int k);
  double &c(int p, int q) { return m_C[p + static_cast<std::size_t>(q) * m_ld]; }

  std::shared_ptr<const MatrixEntries> m_W;
  int m_n;
  int m_single_from;
  bool m_single = false;
  int m_ld = 0;                   ///< leading dimension (slot capacity) of m_C and the inverse
  int m_k = 0;                    ///< slots in use, empty ones included
  std::vector<int> m_slot_index;  ///< per slot: its index, or -1 when empty
  std::vector<int> m_slot_of;     ///< per index: its slot, or -1
  std::vector<int> m_empty;       ///< empty slots below m_k
  std::vector<int> m_J, m_pos;    ///< the compact view: indices in slot order, index -> position
  std::vector<int> m_pos_slot;    ///< position -> slot
  std::vector<double> m_C;   ///< W(J, J) by slots, column-major, leading dimension m_ld
  std::vector<double> m_inv; ///< C⁻¹ by slots in double (when !m_single)
  std::vector<float> m_invf; ///< C⁻¹ by slots in single (when m_single)
  mutable int m_last_iterations = 0;
};

} // namespace hssbem
