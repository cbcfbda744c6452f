/// \file h2_file.hpp
/// A static solve's precomputation on the H² path — the H² operator (every rank its part) and PC
/// h2's factorization of it — saved to files and loaded back instead of the compression and the
/// factorization, for the same problem on as many ranks (docs/persistence.md). Loads may differ.
///
/// Each rank writes and reads its own part: rank 0 the file `path`, rank r > 0 the file
/// `path.rank<r>` (h2_part_path()). Each part is a saved file (io/saved_file.hpp: checksummed
/// HDF5, written the safe way) of kind "static H2 precomputation", format kH2PrecomputationFormat:
/// text attributes `fingerprint_*` (the problem's Fingerprint: the options that shape the
/// operator and the factors, the number of ranks), `rank` (whose part); arrays `partition` (the
/// layout's part of each dof node), `matrix/{d,f,i}` (H2Matrix::pack's streams: doubles, floats,
/// integers) and `factors/{d,f,i}` (H2Factorization::pack's). A load compares the fingerprint,
/// then the partition, before it unpacks anything; the solve after a load is the cold run's, bit
/// for bit (the same matrix, the same factors, the same KSP).
#pragma once

#include "hssbem/core/packed.hpp"
#include "hssbem/h2/h2_system.hpp"
#include "hssbem/h2factor/h2_factorization.hpp"
#include "hssbem/session/fingerprint.hpp"

#include <mpi.h>

#include <memory>
#include <string>
#include <vector>

namespace hssbem {

/// The format the files are written in and the only one read (a change of layout increments it).
inline constexpr int kH2PrecomputationFormat = 1;

/// Rank `rank`'s file of the precomputation saved as `path`.
std::string h2_part_path(const std::string &path, int rank);

/// What shapes the H² path's precomputation, of a static session's fingerprint: its options
/// reduced to the operator's and the factorization's (-mat_*, -bem_mat_type, -pc_type,
/// -pc_h2_* but -pc_h2_estimate_error); the solver's (-ksp_*) and the post-processing's may differ.
Fingerprint h2_precomputation_fingerprint(Fingerprint f);

/// Saves this rank's part (collective on comm: every rank writes its file; a failure on any
/// rank throws on every rank, and no file is left under a final name by a failed rank). `inputs`
/// may not be written over. Throws std::runtime_error ("cannot save '<path>': ...").
void save_h2_precomputation(MPI_Comm comm, const std::string &path, const std::vector<std::string> &inputs, const Fingerprint &f, const std::vector<int> &node_part,
                            const H2DistributedSystem &sys, const H2Factorization &F);

/// A part read and checked against the problem's fingerprint, not unpacked yet.
struct LoadedH2Part {
  std::string path;
  std::vector<int> node_part;
  PackedArrays matrix, factors;
};

/// Reads this rank's part of `path` (collective): the header, the checksum, the fingerprint
/// against `problem` (the first difference refused with one line: Fingerprint::difference), the
/// part's rank. Throws std::runtime_error ("cannot load '<path>': ...") on every rank.
std::shared_ptr<LoadedH2Part> load_h2_precomputation(MPI_Comm comm, const std::string &path, const Fingerprint &problem);

/// The H² system of a loaded part on the layout's partition `node_part` (the same as the file's,
/// else refused: "the partition differs") and ranks (collective): the tree is built again from
/// op's collocation points as the compression builds it (leaf size `options.leaf_size`), the rest
/// unpacked; the part's matrix streams are freed then. Throws std::invalid_argument ("cannot
/// load '<path>': ...") on every rank.
std::shared_ptr<const H2DistributedSystem> unpack_h2_system(LoadedH2Part &part, const BemOperator &op, const H2Options &options, const std::vector<int> &node_part,
                                                            const RankComm &comm);

/// PC h2's factorization of a loaded part, on `sys` (unpack_h2_system's); the part's factor
/// streams are freed then. Collective; throws std::invalid_argument ("cannot load '<path>':
/// ...") on every rank.
std::unique_ptr<H2Factorization> unpack_h2_factorization(LoadedH2Part &part, const H2DistributedSystem &sys);

} // namespace hssbem
