/// \file ulv.hpp
/// ULV-type direct factorization of the system matrix A = K E_S held in HSS form (docs/hss.md).
///
/// The pattern S (which of u or t is unknown per dof) turns the compressed K = [H, G(, Gn)]
/// into the HSS generators of A with no kernel evaluation: leaf blocks and leaf column bases keep
/// the H columns where u is unknown and minus the G columns where t is unknown; transfer matrices
/// and skeleton couplings are shared with K. Then, bottom-up (Chandrasekaran–Gu–Pals, in the form
/// of Xia et al.), each cluster with m active unknowns and row rank k < m
///  - compresses its row basis, Û = Q [Ũ; 0], so that m − k rows of Qᵀ A no longer couple to
///    the rest of the matrix;
///  - factors those rows as [L 0] P (LQ) and eliminates m − k unknowns with the triangular L;
///  - hands k unknowns, rows and bases up; siblings merge into the parent's dense block.
/// The small root block is factored by LU with partial pivoting. Row and column ranks may differ.
/// Cost: about Σ_clusters m³ for the factorization and Σ m·k per solve; all transforms are
/// orthogonal except the triangular L and the root LU.
///
/// Distributed over ranks (hss_distributed.hpp): the elimination of a subtree needs nothing from
/// outside it, so each rank factors its part's subtree up to the part's root with no
/// communication; the parts' roots' reduced blocks (their skeleton rows and columns: Dt, Ut, Vt
/// below) then go to rank 0, which merges and factors the top levels and LU-factors the root. A
/// solve runs the forward sweep of each part, sends the parts' reduced right-hand sides to rank
/// 0, which solves the top, and runs each part's backward sweep from the unknowns rank 0 sends
/// back.
#pragma once

#include "hssbem/core/cluster_exchange.hpp"
#include "hssbem/core/rank_comm.hpp"
#include "hssbem/hss/hss_distributed.hpp"
#include "hssbem/hss/hss_matrix.hpp"

#include <array>
#include <stdexcept>
#include <vector>

namespace hssbem {

/// A pivot (or the root LU) broke down: the matrix is singular to working precision at this
/// compression. The PETSc layer reports it as a preconditioner failure.
class HssBreakdown : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
};

/// A low-rank term Y Zᵀ added to the system matrix (Y and Z: 3N × p, row-major, mesh order),
/// e.g. the rigid-mode regularisation c Φ Φᵀ of a pure-traction problem. It widens every basis by
/// p columns (docs/discretisation.md: the null space handled inside the factorization).
struct LowRankTerm {
  int p = 0;
  std::vector<double> Y, Z;
};

class UlvFactorization {
public:
  /// Factor A = K E_S. `displacement_known` (mesh order, per node and component): true where u is
  /// known and t unknown (column −G), false where u is unknown (column H). K must outlive this
  /// object (its transfer matrices and couplings are used, not copied). Throws HssBreakdown.
  UlvFactorization(const HssMatrix &K, const std::vector<std::array<bool, 3>> &displacement_known, const LowRankTerm *extra = nullptr);
  /// The same for K distributed over the ranks of comm (collective; the pattern and the low-rank
  /// term are whole, mesh order, on every rank). Throws HssBreakdown on every rank when a pivot
  /// broke down on any (fault site Breakdown injects one). comm must outlive this object.
  UlvFactorization(const HssMatrix &K, const RankComm &comm, const std::vector<std::array<bool, 3>> &displacement_known, const LowRankTerm *extra = nullptr);

  /// Solve A x = b in place: b (3 values per point of this rank, cluster order; on one rank all
  /// 3N) becomes x. Collective when distributed.
  void solve(double *b) const;

  /// Bytes held by the factors on this rank.
  std::size_t memory_bytes() const;
  /// Of which those of the top (the clusters above the parts, and the root LU: rank 0's).
  std::size_t top_bytes() const;
  /// Largest dense block factored on this rank (the root's or a merged cluster's).
  int max_front() const { return m_max_front; }
  /// Unknowns of the root block factored by LU (rank 0; 0 elsewhere).
  int root_size() const { return m_root_lu.m; }

private:
  struct Node {
    int m = 0;               ///< active unknowns
    int kr = 0;              ///< row rank (rows still coupled after the elimination)
    bool eliminated = false; ///< m > kr: m − kr unknowns eliminated here
    DenseMatrix qr;          ///< Householder vectors of Û (m × kr)
    std::vector<double> tau_q;
    DenseMatrix lq;          ///< Householder vectors of the decoupled rows, and L ((m−kr) × m)
    std::vector<double> tau_p;
    DenseMatrix Xce;         ///< coupled rows × eliminated unknowns (kr × (m−kr))
    DenseMatrix Ve;          ///< column basis rows of the eliminated unknowns ((m−kr) × kc)
    DenseMatrix Ut;          ///< reduced row basis (r × kr), r = kr if eliminated, else m
    DenseMatrix Vt;          ///< reduced column basis (r × kc)
    DenseMatrix Dt;          ///< reduced diagonal block (r × r), only until the parent merges
  };
  int reduced_size(int c) const { return m_nodes[c].eliminated ? m_nodes[c].kr : m_nodes[c].m; }
  /// Columns of V_of(c): the column skeleton, widened by the low-rank term.
  int col_rank(int c) const { return static_cast<int>(m_K.cluster(c).col_skel.size()) + m_p; }
  void factor_levels(const std::vector<std::vector<int>> &levels, const std::vector<std::array<bool, 3>> &displacement_known);
  void factor_one(int c, const std::vector<std::array<bool, 3>> &displacement_known);
  void leaf_generators(int c, const std::vector<std::array<bool, 3>> &displacement_known, DenseMatrix &D, DenseMatrix &U, DenseMatrix &V) const;
  void factor_root(DenseMatrix D);
  void factor_cluster(int c, DenseMatrix D, DenseMatrix U, DenseMatrix V);
  void merge_children(int c, DenseMatrix &D, DenseMatrix &U, DenseMatrix &V);
  void widen_generators(const LowRankTerm &extra);
  /// The reduced blocks of this rank's parts' roots to the owners of their parents (collective).
  void send_part_roots();
  struct SolveWork;
  void solve_up(int c, const double *b, SolveWork &w) const;
  void solve_down(int c, double *b, SolveWork &w) const;
  /// Transfer matrices and couplings of cluster c, widened by the low-rank term if there is one.
  const DenseMatrix &U_of(int c) const { return m_p > 0 ? m_wide[c].U : m_K.cluster(c).U; }
  const DenseMatrix &V_of(int c) const { return m_p > 0 ? m_wide[c].V : m_K.cluster(c).V; }
  const DenseMatrix &B12_of(int c) const { return m_p > 0 ? m_wide[c].B12 : m_K.cluster(c).B12; }
  const DenseMatrix &B21_of(int c) const { return m_p > 0 ? m_wide[c].B21 : m_K.cluster(c).B21; }

  const HssMatrix &m_K;
  const RankComm &m_comm;
  HssPasses m_passes;
  ClusterExchange m_up, m_down;      ///< the parts' roots' reduced right-hand sides to rank 0; their unknowns back
  int m_p = 0;                       ///< width of the low-rank term
  std::vector<HssCluster> m_wide;    ///< widened generators (leaves: U and V; inner: transfers and couplings)
  std::vector<Node> m_nodes;
  DenseMatrix m_root_lu;
  std::vector<int> m_root_piv;
  int m_max_front = 0;
};

} // namespace hssbem
