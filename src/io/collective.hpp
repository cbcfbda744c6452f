/// \file collective.hpp
/// Private to the result writer: what the ranks of a collective write agree on, so that they
/// take every HDF5 call together and a failure on one rank ends the write on all of them.
#pragma once

#include "hssbem/io/hdf5_output.hpp"

#include <mpi.h>

#include <functional>
#include <map>
#include <string>

namespace hssbem::detail {

/// This process's rank in `comm` (0 for MPI_COMM_NULL); throws OutputError if MPI fails.
int comm_rank(MPI_Comm comm);
/// The size of `comm` (1 for MPI_COMM_NULL); throws OutputError if MPI fails.
int comm_size(MPI_Comm comm);

/// Collective over `comm`: `failure` is this rank's error message, or null when it succeeded.
/// When any rank failed, every rank throws OutputError with the message of the lowest failing
/// rank; otherwise every rank returns.
void agree_on_failure(MPI_Comm comm, const std::string *failure);

/// `text` of rank 0, on every rank of `comm` (collective).
std::string broadcast_from_root(MPI_Comm comm, std::string text);

/// Runs `fn` on this rank, then agree_on_failure() with what it threw: a rank-local step (rank-0
/// file work, say) that every rank leaves the same way.
void run_agreed(MPI_Comm comm, const std::function<void()> &fn);

/// The values written as attributes and small datasets: one copy for all ranks, so that the
/// collective attribute writes receive identical values (timings measured per rank differ).
struct ResultMetadata {
  std::map<std::string, double> attributes_real;
  std::map<std::string, long long> attributes_int;
  std::map<std::string, std::string> attributes_str;
  std::map<std::string, double> timings;
  std::map<std::string, Vec3> reactions;
  std::map<std::string, double> options_real;
  std::map<std::string, long long> options_int;
  std::map<std::string, std::string> options_str;
};

/// Rank 0's metadata of `d`, on every rank of `comm` (collective).
ResultMetadata broadcast_metadata(MPI_Comm comm, const ResultData &d);

/// Collective: throws OutputError naming `path` on every rank unless all ranks hold arrays of
/// the same sizes in `d`, since each writes its rows of datasets they create together.
void check_same_shape(MPI_Comm comm, const std::string &path, const ResultData &d);

} // namespace hssbem::detail
