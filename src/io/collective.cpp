/// \file collective.cpp
/// Agreement between the ranks of a collective result write (see collective.hpp).
#include "collective.hpp"

#include "h5_writer.hpp"

#include <cstdint>
#include <cstring>
#include <string>
#include <new>
#include <type_traits>
#include <vector>

namespace hssbem::detail {

namespace {

void check_mpi(int code, const char *call)
{
  if (code != MPI_SUCCESS)
    throw OutputError(std::string("cannot write output: ") + call + " failed");
}

/// `text` of rank `root` on every rank.
void broadcast_text(MPI_Comm comm, int root, std::string &text)
{
  unsigned long long n = text.size();
  check_mpi(MPI_Bcast(&n, 1, MPI_UNSIGNED_LONG_LONG, root, comm), "MPI_Bcast");
  text.resize(n);
  if (n > 0)
    check_mpi(MPI_Bcast(text.data(), static_cast<int>(n), MPI_CHAR, root, comm), "MPI_Bcast");
}

// --- the metadata as bytes: rank 0 packs, the others unpack ---------------------------------

class Packer {
public:
  void raw(const void *p, std::size_t n) { bytes.append(static_cast<const char *>(p), n); }
  void text(const std::string &s)
  {
    const std::uint64_t n = s.size();
    raw(&n, sizeof n);
    raw(s.data(), s.size());
  }
  template <class T> void map(const std::map<std::string, T> &m)
  {
    const std::uint64_t n = m.size();
    raw(&n, sizeof n);
    for (const auto &[key, value] : m) {
      text(key);
      if constexpr (std::is_same_v<T, std::string>)
        text(value);
      else
        raw(&value, sizeof value); // trivially copyable: double, long long, Vec3
    }
  }
  std::string bytes;
};

class Unpacker {
public:
  explicit Unpacker(const std::string &b) : m_bytes(b) {}
  void raw(void *p, std::size_t n)
  {
    if (m_at + n > m_bytes.size())
      throw OutputError("cannot write output: truncated metadata from rank 0");
    std::memcpy(p, m_bytes.data() + m_at, n);
    m_at += n;
  }
  std::string text()
  {
    std::uint64_t n = 0;
    raw(&n, sizeof n);
    std::string s(n, '\0');
    raw(s.data(), n);
    return s;
  }
  template <class T> void map(std::map<std::string, T> &m)
  {
    std::uint64_t n = 0;
    raw(&n, sizeof n);
    m.clear();
    for (std::uint64_t i = 0; i < n; ++i) {
      std::string key = text();
      T value{};
      if constexpr (std::is_same_v<T, std::string>)
        value = text();
      else
        raw(&value, sizeof value);
      m.emplace(std::move(key), std::move(value));
    }
  }

private:
  const std::string &m_bytes;
  std::size_t m_at = 0;
};

} // namespace

int comm_rank(MPI_Comm comm)
{
  int rank = 0;
  if (comm != MPI_COMM_NULL)
    check_mpi(MPI_Comm_rank(comm, &rank), "MPI_Comm_rank");
  return rank;
}

int comm_size(MPI_Comm comm)
{
  int size = 1;
  if (comm != MPI_COMM_NULL)
    check_mpi(MPI_Comm_size(comm, &size), "MPI_Comm_size");
  return size;
}

void agree_on_failure(MPI_Comm comm, const std::string *failure)
{
  const int rank = comm_rank(comm), size = comm_size(comm);
  const int mine = failure ? rank : size, failed = failure ? 1 : 0;
  int lowest = size, nfailed = 0;
  check_mpi(MPI_Allreduce(&mine, &lowest, 1, MPI_INT, MPI_MIN, comm), "MPI_Allreduce");
  if (lowest == size)
    return;
  check_mpi(MPI_Allreduce(&failed, &nfailed, 1, MPI_INT, MPI_SUM, comm), "MPI_Allreduce");
  std::string message = failure ? *failure : std::string();
  broadcast_text(comm, lowest, message);
  if (nfailed < size) message += " (on rank " + std::to_string(lowest) + ")"; // as the driver's other errors say
  throw OutputError(message);
}

std::string broadcast_from_root(MPI_Comm comm, std::string text)
{
  broadcast_text(comm, 0, text);
  return text;
}

void run_agreed(MPI_Comm comm, const std::function<void()> &fn)
{
  std::string failure;
  bool failed = true;
  try {
    fn();
    failed = false;
  } catch (const std::bad_alloc &) {
    failure = "out of memory";
  } catch (const std::exception &e) {
    failure = e.what();
  }
  agree_on_failure(comm, failed ? &failure : nullptr);
}

ResultMetadata broadcast_metadata(MPI_Comm comm, const ResultData &d)
{
  Packer p;
  if (comm_rank(comm) == 0) {
    p.map(d.attributes_real);
    p.map(d.attributes_int);
    p.map(d.attributes_str);
    p.map(d.timings);
    p.map(d.reactions);
    p.map(d.options_real);
    p.map(d.options_int);
    p.map(d.options_str);
  }
  broadcast_text(comm, 0, p.bytes);
  ResultMetadata m;
  Unpacker u(p.bytes);
  u.map(m.attributes_real);
  u.map(m.attributes_int);
  u.map(m.attributes_str);
  u.map(m.timings);
  u.map(m.reactions);
  u.map(m.options_real);
  u.map(m.options_int);
  u.map(m.options_str);
  return m;
}

namespace {

/// The obstacles' vertices (or triangles) in all.
std::size_t obstacle_rows(const ResultData &d, bool triangles)
{
  std::size_t n = 0;
  for (const ObstacleSurface &o : d.obstacles) n += triangles ? o.triangles.size() : o.vertices.size();
  return n;
}

} // namespace

void check_same_shape(MPI_Comm comm, const std::string &path, const ResultData &d)
{
  const std::vector<std::pair<const char *, std::size_t>> sizes{
      {"/mesh/vertices", d.vertices.size()},
      {"/mesh/triangles", d.triangles.size()},
      {"/mesh/triangle_region", d.triangle_region.size()},
      {"/mesh/sharp_vertex", d.sharp_vertex.size()},
      {"/fields/displacement", d.displacement.size()},
      {"/fields/traction", d.traction.size()},
      {"/fields/traction_corner", d.traction_corner.size()},
      {"/bc/displacement_prescribed", d.displacement_prescribed.size()},
      {"/interior/points", d.interior_points.size()},
      {"/interior/displacement", d.interior_displacement.size()},
      {"/fields/stress", d.stress.stress.size()},
      {"/fields/von_mises", d.stress.von_mises.size()},
      {"/fields/principal_stress", d.stress.principal.size()},
      {"/fields/stress_corner", d.stress.corner.size()},
      {"/interior/stress", d.interior_stress.size()},
      {"/interior/von_mises", d.interior_von_mises.size()},
      {"/interior/grid/displacement", d.interior_grid.displacement.size()},
      {"/interior/grid/stress", d.interior_grid.stress.size()},
      {"/interior/grid/von_mises", d.interior_grid.von_mises.size()},
      {"/interior/grid/inside", d.interior_grid.inside.size()},
      {"/obstacles", d.obstacles.size()},
      {"/obstacles/*/vertices", obstacle_rows(d, false)},
      {"/obstacles/*/triangles", obstacle_rows(d, true)}};
  std::vector<long long> low, high;
  for (const auto &s : sizes)
    low.push_back(static_cast<long long>(s.second)), high.push_back(-low.back());
  const int n = static_cast<int>(low.size());
  check_mpi(MPI_Allreduce(MPI_IN_PLACE, low.data(), n, MPI_LONG_LONG, MPI_MIN, comm), "MPI_Allreduce");
  check_mpi(MPI_Allreduce(MPI_IN_PLACE, high.data(), n, MPI_LONG_LONG, MPI_MIN, comm), "MPI_Allreduce");
  for (int i = 0; i < n; ++i)
    if (low[i] != -high[i])
      fail_output(path, std::string("the ranks hold ") + sizes[i].first + " with " +
                            std::to_string(low[i]) + " to " + std::to_string(-high[i]) +
                            " entries; a collective write needs the same on every rank");
}

} // namespace hssbem::detail
