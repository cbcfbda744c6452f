// Meshes and exact solutions made in code, for tests that must not depend on files.
#pragma once

#include "hssbem/bem/kelvin.hpp"
#include "hssbem/mesh/mesh.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

namespace hssbem::test {

/// Icosahedron refined `levels` times, projected on the sphere of radius r (outward normals).
inline SurfaceMesh icosphere(int levels, double r = 1.0, Vec3 centre = {0, 0, 0})
{
  const double p = (1 + std::sqrt(5.0)) / 2;
  SurfaceMesh m;
  m.vertices = {{-1, p, 0}, {1, p, 0}, {-1, -p, 0}, {1, -p, 0}, {0, -1, p}, {0, 1, p},
                {0, -1, -p}, {0, 1, -p}, {p, 0, -1}, {p, 0, 1}, {-p, 0, -1}, {-p, 0, 1}};
  m.triangles = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                 {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
                 {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      m.vertices.push_back(0.5 * (m.vertices[a] + m.vertices[b]));
      return mid[key] = m.num_vertices() - 1;
    };
    std::vector<std::array<int, 3>> next;
    for (auto t : m.triangles) {
      const int a = midpoint(t[0], t[1]), b = midpoint(t[1], t[2]), c = midpoint(t[2], t[0]);
      next.push_back({t[0], a, c});
      next.push_back({t[1], b, a});
      next.push_back({t[2], c, b});
      next.push_back({a, b, c});
    }
    m.triangles = next;
  }
  for (auto &v : m.vertices) v = centre + r * normalized(v);
  m.triangle_region.assign(m.triangles.size(), -1);
  m.source = "icosphere";
  return m;
}

/// Unit cube [0,1]^3, each face an n x n grid split into triangles, outward normals. Each square
/// is split along its diagonal from its first corner, or (`diamond`) along the other one where
/// its grid indices add up to an even number: for n = 2 the diagonals of a face then form the
/// square inscribed in it.
inline SurfaceMesh unit_cube(int n, bool diamond = false)
{
  SurfaceMesh m;
  std::map<std::array<long, 3>, int> index;
  auto vertex = [&](Vec3 x) {
    const std::array<long, 3> key = {std::lround(x[0] * n), std::lround(x[1] * n), std::lround(x[2] * n)};
    auto it = index.find(key);
    if (it != index.end()) return it->second;
    m.vertices.push_back(x);
    return index[key] = m.num_vertices() - 1;
  };
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      const int u = (axis + 1) % 3, w = (axis + 2) % 3;
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          auto at = [&](int a, int b) {
            Vec3 x{};
            x[axis] = side;
            x[u] = double(a) / n;
            x[w] = double(b) / n;
            return vertex(x);
          };
          int q[4] = {at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)};
          if (side == 0) std::swap(q[1], q[3]); // outward: -axis
          if (diamond && (i + j) % 2 == 0) {
            m.triangles.push_back({q[0], q[1], q[3]});
            m.triangles.push_back({q[1], q[2], q[3]});
          } else {
            m.triangles.push_back({q[0], q[1], q[2]});
            m.triangles.push_back({q[0], q[2], q[3]});
          }
          m.triangle_region.push_back(2 * axis + side);
          m.triangle_region.push_back(2 * axis + side);
        }
    }
  m.source = "unit_cube";
  return m;
}

/// Kelvin's solution for a point force F at s: displacement and traction (normal n) at y.
struct KelvinField {
  Material mat;
  Vec3 s, F;
  Vec3 displacement(const Vec3 &y) const
  {
    const double mu = mat.mu(), nu = mat.nu;
    const Vec3 d = y - s;
    const double r = norm(d);
    const Vec3 g = (1 / r) * d;
    Vec3 u{};
    for (int k = 0; k < 3; ++k)
      for (int l = 0; l < 3; ++l)
        u[k] += ((3 - 4 * nu) * (k == l) + g[k] * g[l]) / (16 * M_PI * mu * (1 - nu) * r) * F[l];
    return u;
  }
  Vec3 traction(const Vec3 &y, const Vec3 &n) const
  {
    const double nu = mat.nu;
    const Vec3 d = y - s;
    const double r = norm(d), drdn = dot(d, n) / r;
    const Vec3 g = (1 / r) * d;
    Vec3 t{};
    for (int k = 0; k < 3; ++k)
      for (int l = 0; l < 3; ++l)
        t[k] += -1 / (8 * M_PI * (1 - nu) * r * r) *
                (drdn * ((1 - 2 * nu) * (k == l) + 3 * g[l] * g[k]) - (1 - 2 * nu) * (g[l] * n[k] - g[k] * n[l])) * F[l];
    return t;
  }
};

} // namespace hssbem::test
