// What a precomputation depends on (see fingerprint.hpp).
#include "hssbem/session/fingerprint.hpp"

#include <algorithm>
#include <cstdio>
#include <map>
#include <sstream>

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

/// A real as %g writes it (1000, 0.3).
std::string num(double v)
{
  char b[32];
  std::snprintf(b, sizeof b, "%g", v);
  return b;
}

/// "<what> differ(s): <stored> in the file, <here> in the problem".
std::string both(const std::string &what, const std::string &stored, const std::string &here)
{
  return what + ": " + stored + " in the file, " + here + " in the problem";
}

/// "name=value" words into a map by name.
std::map<std::string, std::string> option_words(const std::string &options)
{
  std::map<std::string, std::string> out;
  std::istringstream in(options);
  for (std::string w; in >> w;) {
    const std::size_t eq = w.find('=');
    out[w.substr(0, eq)] = eq == std::string::npos ? "" : w.substr(eq + 1);
  }
  return out;
}

/// The first option (by name) set differently in `stored` and `here`, as one line.
std::string option_difference(const std::string &stored, const std::string &here)
{
  const std::map<std::string, std::string> s = option_words(stored), h = option_words(here);
  for (const auto &[name, value] : s) {
    const auto it = h.find(name);
    if (it == h.end()) return "the options differ: -" + name + " " + value + " in the file, no such option in the problem";
    if (it->second != value) return both("the options differ", "-" + name + " " + value, it->second);
  }
  for (const auto &[name, value] : h)
    if (!s.count(name)) return "the options differ: -" + name + " " + value + " in the problem, no such option in the file";
  return both("the options differ", "'" + stored + "'", "'" + here + "'");
}

} // namespace

std::string Fingerprint::difference(const Fingerprint &s) const
{
  if (s.version != version) return "it was made by hssbem " + s.version + ", this is hssbem " + version + " (save it again with this version)";
  if (s.vertices != vertices || s.triangles != triangles)
    return both("the mesh differs", std::to_string(s.vertices) + " vertices and " + std::to_string(s.triangles) + " triangles",
                std::to_string(vertices) + " vertices and " + std::to_string(triangles) + " triangles");
  if (s.mesh != mesh) return "the mesh differs: the same sizes, other coordinates or triangles";
  if (s.feature_angle != feature_angle || s.nodes != nodes)
    return both("the dof nodes differ", std::to_string(s.nodes) + " (feature angle " + num(s.feature_angle) + ")",
                std::to_string(nodes) + " (feature angle " + num(feature_angle) + ")");
  if (s.E != E || s.nu != nu)
    return both("the material differs", "E " + num(s.E) + ", nu " + num(s.nu), "E " + num(E) + ", nu " + num(nu));
  if (s.pattern != pattern) return "the pattern of prescribed components differs";
  if (s.candidates == candidates && s.candidate_set != candidate_set)
    return "the candidate set differs: " + std::to_string(candidates) + " unknowns in both, not the same ones";
  if (s.candidates != candidates || s.candidate_set != candidate_set)
    return both("the candidate set differs", std::to_string(s.candidates) + " unknowns", std::to_string(candidates) + " unknowns");
  if (s.options != options) return option_difference(s.options, options);
  if (s.ranks != ranks) return both("the number of ranks differs", std::to_string(s.ranks), std::to_string(ranks));
  return "";
}

Fingerprint fingerprint(const SessionProblem &problem, const std::vector<char> &pattern, const std::vector<char> &candidates, const OptionValues &options, int ranks)
{
  Fingerprint f;
  f.version = HSSBEM_VERSION;
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
