// What a precomputation depends on (see fingerprint.hpp).
#include "hssbem/session/fingerprint.hpp"

#include <algorithm>

namespace hssbem {

namespace {

/// FNV-1a over bytes, continued from h.
std::uint64_t fnv1a(const void *data, std::size_t bytes, std::uint64_t h = 1469598103934665603ULL)
{
  const unsigned char *p = static_cast<const unsigned char *>(data);
  for (std::size_t i = 0; i < bytes; ++i) h = (h ^ p[i]) * 1099511628211ULL;
  return h;
}

template <class T> std::uint64_t hash_of(const std::vector<T> &v) { return fnv1a(v.data(), v.size() * sizeof(T)); }

/// "<what> differ(s): <stored> in the file, <here> in the problem".
std::string both(const std::string &what, const std::string &stored, const std::string &here)
{
  return what + ": " + stored + " in the file, " + here + " in the problem";
}

} // namespace

std::string Fingerprint::difference(const Fingerprint &s) const
{
  if (s.vertices != vertices || s.triangles != triangles)
    return both("the mesh differs", std::to_string(s.vertices) + " vertices and " + std::to_string(s.triangles) + " triangles",
                std::to_string(vertices) + " vertices and " + std::to_string(triangles) + " triangles");
  if (s.mesh != mesh) return "the mesh differs: the same sizes, other coordinates or triangles";
  if (s.feature_angle != feature_angle || s.nodes != nodes)
    return both("the dof nodes differ", std::to_string(s.nodes) + " (feature angle " + std::to_string(s.feature_angle) + ")",
                std::to_string(nodes) + " (feature angle " + std::to_string(feature_angle) + ")");
  if (s.E != E || s.nu != nu)
    return both("the material differs", "E " + std::to_string(s.E) + ", nu " + std::to_string(s.nu), "E " + std::to_string(E) + ", nu " + std::to_string(nu));
  if (s.pattern != pattern) return "the pattern of prescribed components differs";
  if (s.candidates != candidates || s.candidate_set != candidate_set)
    return both("the candidate set differs", std::to_string(s.candidates) + " unknowns", std::to_string(candidates) + " unknowns");
  if (s.options != options) return both("the options differ", "'" + s.options + "'", "'" + options + "'");
  if (s.ranks != ranks) return both("the number of ranks differs", std::to_string(s.ranks), std::to_string(ranks));
  return "";
}

Fingerprint fingerprint(const SessionProblem &problem, const std::vector<char> &pattern, const std::vector<char> &candidates, const OptionValues &options, int ranks)
{
  Fingerprint f;
  const SurfaceMesh &m = problem.mesh();
  f.vertices = m.num_vertices();
  f.triangles = m.num_triangles();
  f.mesh = fnv1a(m.triangles.data(), m.triangles.size() * sizeof(m.triangles[0]), hash_of(m.vertices));
  f.nodes = problem.disc().num_nodes();
  f.feature_angle = problem.disc().feature_angle_deg();
  f.E = problem.material().E;
  f.nu = problem.material().nu;
  f.unknowns = problem.unknowns();
  f.pattern = hash_of(pattern);
  f.candidates = std::count(candidates.begin(), candidates.end(), 1);
  f.candidate_set = hash_of(candidates);
  for (const auto &[name, v] : options) f.options += (f.options.empty() ? "" : " ") + name + "=" + option_value_text(v);
  f.ranks = ranks;
  return f;
}

} // namespace hssbem
