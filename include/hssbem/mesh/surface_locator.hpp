/// \file surface_locator.hpp
/// Where a point lies with respect to the closed surface: the nearest surface point (triangle,
/// barycentric coordinates, distance) and the generalised winding number (1 inside, 0 outside,
/// 1/2 on a face), both through a tree over the triangles with a ball and a box per cluster.
///
/// The winding number is the sum of the triangles' solid angles over 4π, exact (Van Oosterom and
/// Strackee) for the triangles near the point and through each far cluster's dipole Σ A_e n_e
/// (Barnes–Hut, clusters beyond `far_ratio` of their radius): off by a few hundredths at most,
/// which is all a threshold at 1/2 needs. O(log nt) per point on a well-shaped surface.
#pragma once

#include "hssbem/mesh/mesh.hpp"
#include "hssbem/core/cluster_tree.hpp"

#include <limits>
#include <vector>

namespace hssbem {

class SurfaceLocator {
public:
  explicit SurfaceLocator(const SurfaceMesh &mesh);

  struct Nearest {
    int triangle = -1;
    Vec3 point{};  ///< the nearest point of the surface
    Vec3 bary{};   ///< its barycentric coordinates in `triangle`
    double distance = 0;
  };
  /// The surface point nearest to x (ties: the first triangle found); with a `limit`, only
  /// points closer than it are looked for (triangle −1 when there is none).
  Nearest nearest(const Vec3 &x, double limit = std::numeric_limits<double>::infinity()) const;
  /// The generalised winding number of the surface at x.
  double winding_number(const Vec3 &x) const;
  /// Whether x lies inside the body (winding number above 1/2).
  bool inside(const Vec3 &x) const { return winding_number(x) > 0.5; }
  /// The same given n = nearest(x): by the side of n's triangle where n lies inside that triangle
  /// and x clearly off its plane (exact for a closed, consistently oriented surface: the segment
  /// from x to n meets no other surface point), else by the winding number.
  bool inside(const Vec3 &x, const Nearest &n) const;

  /// The diagonal of the surface's bounding box.
  double size() const { return m_size; }
  const SurfaceMesh &mesh() const { return *m_mesh; }

private:
  struct Ball {
    Vec3 centre{};    ///< area-weighted centroid of the cluster's triangles
    double radius = 0; ///< largest distance from centre to one of their corners
    Vec3 dipole{};    ///< Σ A_e n_e
    Vec3 lo{}, hi{};  ///< bounding box of the triangles' corners (tighter than the ball for flat patches)
  };
  /// A lower bound of the distance from x to cluster c's triangles: the larger of the ball's and the box's.
  double distance_to(int c, const Vec3 &x) const;
  void nearest_in(int c, const Vec3 &x, Nearest &best) const;
  double winding_in(int c, const Vec3 &x) const;

  const SurfaceMesh *m_mesh;
  ClusterTree m_tree;
  std::vector<Ball> m_ball;
  double m_size = 0;
};

} // namespace hssbem
