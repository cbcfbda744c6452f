/// \file dense_scene.hpp
/// Real-time scenes: one geometry, a boundary-condition pattern and values that change every
/// frame (a broad contact moving over the surface), re-solved at interactive rates.
///
/// Method. With K = [H, −G] (BemOperator), a pattern S picks per unknown j the column A_S(:, j)
/// = H(:, j) (u_j unknown) or −G(:, j) (t_j unknown), and the right-hand side is
/// b_S = −Σ_j K_S'(:, j) v_j with v_j the known value and K_S'(:, j) the column S does not use
/// (pressure loads add −Σ p_n Gn(:, n)). The scene factors once the reference pattern S₀ (the
/// base rules): A₀ = LU, then W = A₀⁻¹ K₀' (the columns S₀ does not use; N right-hand sides) and,
/// with pressure loads, W_p = A₀⁻¹ Gn. A frame's pattern S differs from S₀ on the switched set
/// J; then A₀⁻¹ A_S = I + (W(:, J) − E_J) E_Jᵀ and, by Sherman–Morrison–Woodbury,
///     y = A₀⁻¹ b_S = −Σ_{j∉J} W(:, j) v_j − Σ_{j∈J} e_j v_j − Σ_n W_p(:, n) p_n,
///     s = W(J, J)⁻¹ y(J),   x = y − W(:, J) s,   x(J) += s,
/// so the capacitance matrix is the principal submatrix C = W(J, J) (and x(J) = s alone gives
/// the switched unknowns — a contact's forces — in O(|J| · nnz(v)): the haptic loop). C⁻¹ is
/// kept up to date as J changes (capacitance.hpp): a moving patch costs O(|J|² · changed).
/// Per frame that is O(N (nnz(v) + |J|)) memory traffic plus the capacitance update, against
/// (2/3) N³ for a dense LU per frame.
///
/// Strategies per frame (SceneStrategy): `solve` (pattern as the frame before: only the values
/// changed), `update` (Woodbury with the capacitance inverse updated or rebuilt), `refactor`
/// (dense LU of A_S: what the earlier frame-by-frame approach does; its factors serve the next
/// frames while the pattern stays), `krylov` (GMRES on A_S, preconditioned by the last
/// factorization made — the Woodbury form of the previous pattern or the last refactor — and
/// started from the previous frame's fields). `auto` picks the cheapest by a cost model whose
/// rates (memory bandwidth, flop rate) are measured at set-up and corrected after every frame by
/// the measured time (report(): predicted and measured seconds).
///
/// Precision. From SceneOptions::single_from switched unknowns on, C⁻¹ is kept in single
/// precision and refined in double (capacitance.hpp); from single_fields_from on, the product
/// x −= W(:, J) s reads W(:, J) from a single-precision copy of W (each column converted on its
/// first use, or all of them at set-up when the scene has candidates), its rows in cluster order
/// so that the product skips J's rows in runs: half the bytes of the frame's largest product. The
/// switched unknowns x(J) = s keep double accuracy; the others carry W's rounding (~5e-9
/// relative on the cardioid, docs/scenes.md).
///
/// Memory: W (8 N² bytes, or 8 N per candidate: SceneOptions::candidates) and the LU of A₀ (8 N² bytes), H and G (16 N² bytes, for refactor, krylov and residuals; see
/// SceneOptions::keep_operator), W_p and Gn (8 N² / 3 bytes each) with pressure loads, one
/// N² factor after a refactor, and W's single-precision copy (4 N per column converted). Thread-safety:
/// one frame at a time.
#pragma once

#include "hssbem/bem/bem_operator.hpp"
#include "hssbem/core/krylov.hpp"
#include "hssbem/core/option_table.hpp"
#include "hssbem/reference/capacitance.hpp"
#include "hssbem/reference/reference.hpp"

#include <array>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace hssbem {

class Progress; // core/progress.hpp

enum class SceneStrategy { Auto, Solve, Update, Refactor, Krylov };

/// "auto", "solve", "update", "refactor", "krylov".
const char *scene_strategy_name(SceneStrategy s);
/// The strategy named s, or nothing.
std::optional<SceneStrategy> parse_scene_strategy(const std::string &s);

struct SceneOptions {
  SceneStrategy strategy = SceneStrategy::Auto; ///< forced strategy, or auto
  bool with_pressure = false;  ///< some frame has pressure loads: compute W_p = A₀⁻¹ Gn at set-up
  bool keep_operator = true;   ///< keep H and G (needed by refactor, krylov and residual())
  int refresh_every = option_default::scene_refresh; ///< incremental capacitance updates before a rebuild from scratch
  /// Switched sets of at least this size keep the capacitance inverse in single precision,
  /// refined in double per solve (capacitance.hpp); INT_MAX: always double.
  int single_from = option_default::scene_single_from;
  /// Switched sets of at least this size take the fields' product x −= W(:, J) s from a copy of
  /// W(:, J) in single precision (half the bytes; the switched unknowns x(J) = s stay refined in
  /// double, the other unknowns carry W's single-precision rounding, ~1e-7 relative); INT_MAX:
  /// always double.
  int single_fields_from = option_default::scene_single_fields_from;
  /// Per unknown (3 · node + component), 1 where some frame may switch it (prescribe the other
  /// quantity than the reference pattern) or give it a non-zero known value: W is computed and
  /// kept for those columns only (2 N² flops and 8 N bytes per candidate, instead of every
  /// column), and a frame that switches or loads another unknown is refused. Empty: every unknown.
  std::vector<char> candidates;
  double krylov_rtol = option_default::scene_krylov_rtol; ///< GMRES relative tolerance (true residual) of the krylov strategy
  int krylov_max_it = 200;     ///< and its iteration limit (reaching it is an error)
};

/// What a frame did.
struct SceneFrameReport {
  SceneStrategy strategy = SceneStrategy::Solve; ///< what was done (never auto)
  long long switched = 0;   ///< |J|: unknowns of another type than in the reference pattern
  long long changed = 0;    ///< unknowns whose type differs from the frame before
  long long values = 0;     ///< nonzero known values (right-hand side columns)
  long long iterations = 0; ///< GMRES iterations (krylov)
  bool rebuilt = false;     ///< update: the capacitance inverse was rebuilt, not updated
  int refinements = 0;      ///< refinement steps of the frame's capacitance solve (capacitance.hpp)
  /// Where an update's or solve's time went: the capacitance update (or rebuild), the
  /// capacitance solve s = W(J, J)⁻¹ y(J), and the fields' product x −= W(:, J) s.
  double update_seconds = 0, capacitance_seconds = 0, fields_seconds = 0;
  double seconds = 0;       ///< wall time of the frame (update and solve)
  double predicted = 0;     ///< the cost model's seconds for the strategy taken
};

/// Marks in `candidates` (3 per node; sized here when empty) the unknowns that `frame` switches
/// against the reference pattern or loads with a non-zero known value (a traction under a
/// pressure load goes through the pressure columns instead): the union over a scene's frames is
/// its SceneOptions::candidates.
void mark_scene_candidates(const SystemSelection &reference, const SystemSelection &frame, std::vector<char> &candidates);

class DenseScene {
public:
  /// Set-up: assembles H and G (and Gn), factors the reference pattern `reference` (its values
  /// are not used) and forms W. Throws std::runtime_error when the reference system is singular
  /// (a pattern that leaves the body free to move: check the constraints first).
  DenseScene(const BemOperator &op, const SystemSelection &reference, const SceneOptions &options = {},
             std::unique_ptr<KrylovSolver> krylov = nullptr);
  /// What a set-up computed, kept to be saved and loaded (session/precomputation_file.hpp): the
  /// reference factorization (its LU, and H, G, Gn as the options keep them), W and W_p (rows in
  /// unknown order) and the cost model's measured rates.
  struct Saved {
    std::unique_ptr<DenseReference> reference;
    std::vector<double> W, Wp;
    std::array<double, 3> rates{}; ///< bandwidth(), flop_rate() and the LU's flop/s
  };
  /// A scene set up before (the parts of a Saved): no assembly, no factorization, no columns;
  /// the single-precision copy and the capacitance are made as the set-up makes them, so the
  /// frames are the set-up's to the bit. Throws std::invalid_argument when the parts do not fit
  /// the operator and the options (sizes, candidates, pressure, the operator kept).
  DenseScene(const BemOperator &op, Saved saved, const SceneOptions &options = {}, std::unique_ptr<KrylovSolver> krylov = nullptr);
  ~DenseScene();
  DenseScene(const DenseScene &) = delete;
  DenseScene &operator=(const DenseScene &) = delete;

  /// Solve the frame `sel` (pattern, values, pressure; same nodes as the operator): x gets the
  /// unknowns, 3 per node in node order (t where sel prescribes u, u elsewhere). `force` (not
  /// auto) overrides the options' strategy for this frame; solve is refused (std::invalid_argument)
  /// when the pattern changed. Returns what was done.
  const SceneFrameReport &solve(const SystemSelection &sel, std::vector<double> &x, SceneStrategy force = SceneStrategy::Auto);

  /// The haptic loop: after a frame with the same pattern, the unknowns of the switched set J
  /// only (a contact's tractions, say) for new values in sel, in O(|J| · nnz(v)); out gets
  /// (index, value) pairs in the order of switched(). Throws std::invalid_argument when sel's
  /// pattern is not the one of the last update or solve.
  void solve_switched(const SystemSelection &sel, std::vector<double> &out);
  /// The switched set of the current capacitance inverse (unknown indices 3 node + component).
  const std::vector<int> &switched() const { return m_cap.indices(); }

  /// ‖A_S x − b_S‖ / ‖b_S‖ from H and G (needs keep_operator).
  double residual(const SystemSelection &sel, const std::vector<double> &x) const;

  int num_unknowns() const { return m_n; }
  /// The set-up's parts, for saving (Saved): the reference, W, W_p, the rates.
  const DenseReference &reference() const { return *m_reference; }
  const std::vector<double> &columns() const { return m_W; }
  const std::vector<double> &pressure_columns() const { return m_Wp; }
  std::array<double, 3> rates() const { return {m_bandwidth, m_flops, m_lu_flops}; }
  double setup_seconds() const { return m_setup_seconds; }
  /// Of the set-up: the reference (assembly of H and G, LU of A₀) and W's columns.
  double reference_seconds() const { return m_reference_seconds; }
  double columns_seconds() const { return m_columns_seconds; }
  /// Bytes held (W, H, G, W_p, Gn, factors, capacitance).
  std::size_t memory_bytes() const;
  /// Measured rates of the cost model: bytes/s of a gathered matrix-vector product over W's
  /// columns, and flop/s of GEMM and of LU.
  double bandwidth() const { return m_bandwidth; }
  double flop_rate() const { return m_flops; }
  /// Predicted seconds of each strategy for the frame `sel` after the current state (solve:
  /// infinity when the pattern changed).
  std::array<double, 5> predict(const SystemSelection &sel) const;

private:
  void factor_reference(const BemOperator &op, const SystemSelection &reference, const Progress &progress);
  /// m_wcol from the options' candidates; the unknowns whose columns W stores, in order.
  std::vector<int> candidate_columns();
  /// The set-up's end, after the reference and W: the single-precision copy, the capacitance.
  void finish_set_up(const BemOperator &op);
  void measure_rates();
  std::vector<char> pattern_of(const SystemSelection &sel) const;
  /// y = A₀⁻¹ b_S for the pattern of the switched set J (m_cap) and sel's values.
  void reference_solve(const SystemSelection &sel, const std::vector<char> &pattern, std::vector<double> &y) const;
  void woodbury_solve(const SystemSelection &sel, const std::vector<char> &pattern, std::vector<double> &x) const;
  /// y ← (I + Z E_Jᵀ)⁻¹ y for the capacitance's switched set J: the Woodbury correction of a
  /// vector already multiplied by A₀⁻¹.
  void capacitance_correct(double *y) const;
  void update_capacitance(const std::vector<char> &pattern);
  void refactor(const SystemSelection &sel, const std::vector<char> &pattern, std::vector<double> &x);
  void lu_solve(const SystemSelection &sel, const std::vector<char> &pattern, std::vector<double> &x) const;
  void krylov(const SystemSelection &sel, const std::vector<char> &pattern, std::vector<double> &x);
  /// b_S (needs H and G).
  void rhs(const SystemSelection &sel, const std::vector<char> &pattern, std::vector<double> &b) const;
  void apply_system(const std::vector<char> &pattern, const double *x, double *y) const;
  /// z = the last factorization's inverse applied to r: a preconditioner for krylov.
  void apply_previous(const double *r, double *z) const;
  /// predict() for the pattern of sel, already built.
  std::array<double, 5> predict(const SystemSelection &sel, const std::vector<char> &pattern) const;
  double predict_update(const std::vector<char> &pattern, bool *rebuild) const;

  int m_n = 0, m_nodes = 0;
  SceneOptions m_opt;
  std::unique_ptr<KrylovSolver> m_krylov;
  std::vector<char> m_ref;           ///< reference pattern: 1 where u is known (t unknown)
  std::unique_ptr<DenseReference> m_reference; ///< A₀'s LU, and H, G, Gn (keep_operator)
  std::vector<double> m_W, m_Wp;     ///< A₀⁻¹ K₀' (the candidates' columns) and A₀⁻¹ Gn, column-major
  std::vector<int> m_wcol;           ///< per unknown: its column in m_W, or -1 (no candidate)
  /// The columns of m_W holding W(:, js) (each a candidate).
  std::vector<int> stored(const std::vector<int> &js) const;
  /// Throws std::invalid_argument when the frame switches or loads an unknown that is no candidate.
  void check_candidates(const SystemSelection &sel, const std::vector<char> &pattern) const;
  /// W(J, J)⁻¹ for the current switched set; mutable: a solve whose single-precision refinement
  /// stops contracting rebuilds it (in double) on the spot.
  mutable CapacitanceInverse m_cap;
  /// s = W(J, J)⁻¹ r with the current capacitance, rebuilding it when its refinement fails.
  void capacitance_solve(const double *r, double *s) const;
  /// y −= W(:, J) s, y(J) = s from W's single-precision copy (SceneOptions::single_fields_from).
  void single_fields_correct(const std::vector<double> &s, double *y) const;
  /// Converts the stored columns `cols` into the single-precision copy where not done yet.
  void single_columns(const std::vector<int> &cols) const;
  /// Sets up the single-precision copy (and fills it when the scene has candidates).
  void single_copy(const BemOperator &op);
  /// W's stored columns in single precision, rows in cluster order (m_row_order[r]: the unknown
  /// of row r; m_row_position its inverse); m_wf_ready: the columns converted so far. Mutable:
  /// converted on first use.
  mutable std::unique_ptr<float[]> m_Wf;
  mutable std::vector<char> m_wf_ready;
  std::vector<int> m_row_order, m_row_position;
  mutable int m_last_refinements = 0;
  mutable double m_cap_seconds = 0, m_fields_seconds = 0; ///< of the frame (the report's)
  std::vector<char> m_cap_pattern;   ///< the pattern m_cap serves
  int m_updates_since_rebuild = 0;
  std::vector<double> m_lu;          ///< LU of A_S after a refactor, column-major
  std::vector<int> m_piv;
  std::vector<char> m_lu_pattern;    ///< its pattern (empty: none)
  std::vector<char> m_last_pattern;  ///< pattern of the previous frame
  std::vector<Vec3> m_last_u, m_last_t; ///< fields of the previous frame (krylov's initial guess)
  enum class Last { None, Woodbury, Lu } m_last_factor = Last::Woodbury; ///< the last factorization made
  double m_bandwidth = 1e10, m_flops = 1e10, m_lu_flops = 1e10;
  std::array<double, 5> m_correction{{1, 1, 1, 1, 1}}; ///< measured / predicted, per strategy
  double m_setup_seconds = 0, m_reference_seconds = 0, m_columns_seconds = 0;
  SceneFrameReport m_report;
};

} // namespace hssbem
