/// \file phase.hpp
/// Named phases of the compression engines (HSS and H²), of the H² factorization, of scenes and of contact, reported to an optional hook so a host
/// (the PETSc layer: one PetscLogEvent per phase) can time them without the engines depending on
/// it. The engines open and close phases on the calling thread only, never inside their OpenMP
/// regions.
#pragma once

namespace hssbem {

enum class Phase {
  Tree,          ///< HSS: cluster tree (geometric bisection)
  Compression,   ///< HSS: skeletons (proxy and near-field samples, interpolative decompositions) and couplings
  NearField,     ///< HSS: leaf diagonal blocks and rigid-body terms
  Truncation,    ///< recompression of an HSS matrix to a looser tolerance
  Factorization, ///< ULV factorization
  Solve,         ///< ULV solve
  Matvec,        ///< HSS product
  FactorizationTop, ///< distributed ULV factorization: the parts' roots' blocks to rank 0 and the top's factorization there (inside Factorization)
  SolveTop,         ///< distributed ULV solve: the parts' roots' right-hand sides to rank 0, the top's solve there, the unknowns back (inside Solve)
  H2Tree,          ///< H²: cluster tree and block partition
  H2Compress,      ///< H²: nested bases (interpolative decompositions) and far blocks
  H2NearField,     ///< H²: near blocks and rigid-body terms
  H2Matvec,        ///< H² product
  H2Factorization, ///< H² factorization, the whole of it (the five below but the solve are inside)
  H2Sketch,        ///< H² factorization: random sketch of the far-field couplings
  H2Eliminate,     ///< H² factorization: skeletons and eliminations of the boxes, level by level
  H2Merge,         ///< H² factorization: a level's remaining unknowns and blocks onto the parents
  H2Top,           ///< H² factorization: dense LU of the unknowns left at the top
  H2Solve,         ///< solve with the H² factorization
  SceneSetup,      ///< scene: operator, reference factorization, W = A₀⁻¹ K₀'
  SceneUpdate,     ///< scene: capacitance inverse updated or rebuilt for a new pattern
  SceneApply,      ///< scene: the Woodbury (or LU) solve of a frame
  SceneRefactor,   ///< scene: dense LU of a frame's system
  SceneKrylov,     ///< scene: GMRES preconditioned by the last factorization
  ContactDetect,   ///< contact: contact points of a frame (obstacles' gaps, pairs of bodies)
  ContactSolve,    ///< contact: compliance and the active-set (or Newton) iterations
  ContactFields,   ///< contact: the fields from the free response and W's loaded columns
  ContactCorrect,  ///< contact: accurate solves correcting a frame on approximate columns (H2Reference)
  Count
};

/// Called with begin = true when a phase opens and false when it closes.
using PhaseHook = void (*)(Phase phase, bool begin);

/// Install (or with nullptr remove) the hook; not thread-safe, call it once at start-up.
void set_phase_hook(PhaseHook hook);

/// Opens a phase for the lifetime of the object.
class PhaseScope {
public:
  explicit PhaseScope(Phase phase);
  ~PhaseScope();
  PhaseScope(const PhaseScope &) = delete;
  PhaseScope &operator=(const PhaseScope &) = delete;

private:
  Phase m_phase;
};

} // namespace hssbem
