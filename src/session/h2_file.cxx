// A static solve's H² precomputation to files and back (see h2_file.hpp).
#include "hssbem/session/h2_file.hpp"

#include "hssbem/compress/compression.hpp"
#include "hssbem/core/tree_ownership.hpp"
#include "hssbem/io/saved_file.hpp"
#include "hssbem/session/petsc_call.hpp"
#include "hssbem/session/precomputation_file.hpp"

#include <algorithm>
#include <optional>
#include <sstream>
#include <stdexcept>

namespace hssbem {

namespace {

constexpr const char *kKind = "static H2 precomputation";

int comm_rank(MPI_Comm comm)
{
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  return rank;
}

/// Whether option `name` shapes the operator or the factorization.
bool shapes_precomputation(const std::string &name)
{
  if (name == "pc_h2_estimate_error") return false;
  return name.rfind("mat_", 0) == 0 || name == "bem_mat_type" || name == "pc_type" || name.rfind("pc_h2_", 0) == 0;
}

void write_stream(SavedFileWriter &w, const std::string &at, const PackedArrays &a)
{
  w.doubles(at + "/d", a.d.data(), a.d.size());
  w.floats(at + "/f", a.f.data(), a.f.size());
  w.ints(at + "/i", a.i.data(), a.i.size());
}

PackedArrays read_stream(const SavedFileReader &r, const std::string &at)
{
  PackedArrays a;
  a.d = r.doubles(at + "/d");
  a.f = r.floats(at + "/f");
  a.i = r.ints(at + "/i");
  return a;
}

} // namespace

std::string h2_part_path(const std::string &path, int rank) { return rank == 0 ? path : path + ".rank" + std::to_string(rank); }

Fingerprint h2_precomputation_fingerprint(Fingerprint f)
{
  std::istringstream in(f.options);
  std::string kept;
  for (std::string w; in >> w;)
    if (shapes_precomputation(w.substr(0, w.find('=')))) kept += (kept.empty() ? "" : " ") + w;
  f.options = kept;
  return f;
}

void save_h2_precomputation(MPI_Comm comm, const std::string &path, const std::vector<std::string> &inputs, const Fingerprint &f, const std::vector<int> &node_part,
                            const H2DistributedSystem &sys, const H2Factorization &F)
{
  const int rank = comm_rank(comm);
  const std::string mine = h2_part_path(path, rank);
  run_collectively(comm, [&] {
    SavedFileWriter w(mine, inputs, kKind, kH2PrecomputationFormat);
    write_fingerprint(w, f);
    w.text("rank", std::to_string(rank));
    w.ints("partition", node_part.data(), node_part.size());
    { // one packed copy at a time beside the precomputation: the matrix's, then the factors'
      PackedArrays matrix;
      PackWriter wm(matrix);
      sys.matrix().pack(wm);
      write_stream(w, "matrix", matrix);
    }
    {
      PackedArrays factors;
      PackWriter wf(factors);
      F.pack(wf);
      write_stream(w, "factors", factors);
    }
    w.commit();
  });
}

std::shared_ptr<LoadedH2Part> load_h2_precomputation(MPI_Comm comm, const std::string &path, const Fingerprint &problem)
{
  const int rank = comm_rank(comm);
  auto part = std::make_shared<LoadedH2Part>();
  part->path = h2_part_path(path, rank);
  run_collectively(comm, [&] {
    const SavedFileReader r(part->path, kKind, kH2PrecomputationFormat);
    const std::string why = problem.difference(read_fingerprint(r));
    if (!why.empty()) r.fail(why);
    if (r.text("rank") != std::to_string(rank)) r.fail("it is rank " + r.text("rank") + "'s part, not rank " + std::to_string(rank) + "'s");
    part->node_part = r.ints("partition");
    part->matrix = read_stream(r, "matrix");
    part->factors = read_stream(r, "factors");
  });
  return part;
}

std::shared_ptr<const H2DistributedSystem> unpack_h2_system(LoadedH2Part &part, const BemOperator &op, const H2Options &options, const std::vector<int> &node_part,
                                                            const RankComm &comm)
{
  std::optional<H2Matrix> K;
  collectively<std::invalid_argument>(comm, [&] {
    try {
      if (part.node_part != node_part) throw std::invalid_argument("the partition differs: the file's parts of the dof nodes are not this run's (another METIS?)");
      const std::vector<Vec3> points = collocation_points(op.discretization());
      const int nparts = node_part.empty() ? 1 : 1 + *std::max_element(node_part.begin(), node_part.end());
      const ClusterTreeOptions topts{options.leaf_size};
      ClusterTree tree = nparts > 1 ? ClusterTree(points, node_part, nparts, topts) : ClusterTree(points, topts);
      std::vector<int> owner = cluster_owners(tree, comm.size());
      PackReader r(part.matrix);
      K.emplace(H2Matrix::unpack(std::move(tree), std::move(owner), comm.rank(), r));
      if (!r.done()) throw std::invalid_argument("damaged: the matrix is followed by more");
      part.matrix = PackedArrays(); // unpacked: its copy goes
    } catch (const std::invalid_argument &e) {
      throw std::invalid_argument("cannot load '" + part.path + "': " + e.what());
    }
  });
  return make_shared_collectively<H2DistributedSystem>(comm, std::move(*K), comm);
}

std::unique_ptr<H2Factorization> unpack_h2_factorization(LoadedH2Part &part, const H2DistributedSystem &sys)
{
  PackReader r(part.factors);
  std::unique_ptr<H2Factorization> F;
  try {
    F = make_unique_collectively<H2Factorization>(sys.product().comm(), sys.matrix(), sys.product().comm(), sys.first_point(), sys.num_points(), r);
  } catch (const std::invalid_argument &e) {
    throw std::invalid_argument("cannot load '" + part.path + "': " + e.what());
  }
  part.factors = PackedArrays(); // unpacked: its copy goes
  return F;
}

} // namespace hssbem
