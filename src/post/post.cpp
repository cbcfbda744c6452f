#include "hssbem/post/post.hpp"

#include "hssbem/bem/rigid_modes.hpp"

#include <cmath>
#include <limits>

namespace hssbem {

NodalSolution split_unknowns(const SystemSelection &sel, const std::vector<double> &x)
{
  const std::size_t n = sel.known.size();
  NodalSolution s{std::vector<Vec3>(n), std::vector<Vec3>(n)};
  for (std::size_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) {
      const double unknown = x[3 * i + c];
      s.u[i][c] = sel.displacement_known[i][c] ? sel.known[i][c] : unknown;
      s.t[i][c] = sel.displacement_known[i][c] ? unknown : sel.known[i][c];
    }
  return s;
}

NodalSolution with_particular(NodalSolution h, const Discretization &disc, const UniformBodyForce &force)
{
  const ParticularTraces p = particular_traces(disc, force);
  for (std::size_t i = 0; i < p.u.size(); ++i) h.u[i] = h.u[i] + p.u[i], h.t[i] = h.t[i] + p.t[i];
  return h;
}

void remove_whole_rigid_motion(const Discretization &disc, const UniformBodyForce &force, std::vector<Vec3> &u_h)
{
  const ParticularTraces p = particular_traces(disc, force);
  for (std::size_t i = 0; i < p.u.size(); ++i) u_h[i] = u_h[i] + p.u[i];
  remove_rigid_motion(disc, u_h);
  for (std::size_t i = 0; i < p.u.size(); ++i) u_h[i] = u_h[i] - p.u[i];
}

std::vector<Vec3> vertex_average(const Discretization &disc, const std::vector<Vec3> &nodal)
{
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<Vec3> out(disc.mesh().vertices.size(), Vec3{nan, nan, nan});
  for (int v = 0; v < disc.mesh().num_vertices(); ++v) {
    const int k = disc.node_count(v);
    if (k == 0) continue;
    Vec3 sum{};
    for (int i = disc.first_node(v); i < disc.first_node(v) + k; ++i) sum = sum + nodal[i];
    out[v] = (1.0 / k) * sum;
  }
  return out;
}

std::vector<std::array<Vec3, 3>> corner_values(const Discretization &disc, const std::vector<Vec3> &nodal)
{
  std::vector<std::array<Vec3, 3>> out(disc.mesh().triangles.size());
  for (std::size_t t = 0; t < out.size(); ++t)
    for (int c = 0; c < 3; ++c) out[t][c] = nodal[disc.element_node(static_cast<int>(t), c)];
  return out;
}

std::map<std::string, Vec3> reactions(const Discretization &disc, const std::vector<Vec3> &t)
{
  const SurfaceMesh &mesh = disc.mesh();
  std::map<int, std::string> names;
  for (const auto &[name, tag] : mesh.region_tags) names[tag] = name;
  std::map<std::string, Vec3> out;
  for (int e = 0; e < mesh.num_triangles(); ++e) {
    Vec3 f{};
    for (int c = 0; c < 3; ++c) f = f + (mesh.triangle_area(e) / 3.0) * t[disc.element_node(e, c)];
    out["total"] = out["total"] + f;
    const int tag = e < static_cast<int>(mesh.triangle_region.size()) ? mesh.triangle_region[e] : -1;
    if (tag < 0) continue;
    const auto it = names.find(tag);
    const std::string key = it != names.end() ? it->second : std::to_string(tag);
    out[key] = out[key] + f;
  }
  return out;
}

std::vector<Vec3> interior_displacement(const BemOperator &op, const NodalSolution &s, const std::vector<Vec3> &points)
{
  const Discretization &disc = op.discretization();
  std::vector<Vec3> out(points.size(), Vec3{});
  ElementIntegrals ei;
  for (std::size_t p = 0; p < points.size(); ++p)
    for (int e = 0; e < disc.mesh().num_triangles(); ++e) {
      op.element_integrals(points[p], -1, e, ei);
      for (int a = 0; a < 3; ++a) {
        const int j = disc.element_node(e, a);
        for (int k = 0; k < 3; ++k)
          for (int c = 0; c < 3; ++c) out[p][k] += ei.G[a][3 * k + c] * s.t[j][c] - ei.H[a][3 * k + c] * s.u[j][c];
      }
    }
  return out;
}

double inside_indicator(const BemOperator &op, const Vec3 &x)
{
  Mat3 c{};
  ElementIntegrals ei;
  for (int e = 0; e < op.discretization().mesh().num_triangles(); ++e) {
    op.element_integrals(x, -1, e, ei);
    for (int a = 0; a < 3; ++a)
      for (int m = 0; m < 9; ++m) c[m] -= ei.H[a][m];
  }
  return (c[0] + c[4] + c[8]) / 3.0;
}

} // namespace hssbem
