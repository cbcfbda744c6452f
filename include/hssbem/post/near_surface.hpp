/// \file near_surface.hpp
/// Interior points as an evaluation of Somigliana's identities sees them: outside the body, on
/// its surface, in a band along the surface, or deep inside.
///
/// Close to the surface the identities' integrands are nearly singular and cancel: at depth d
/// the stress integral sums terms ~ |u|/d to a result ~ |u|/L, so the quadrature must be L/d times
/// more accurate than the answer, and the P1 data's kinks at the element edges (which the exact
/// field does not have) show through as d falls below the element size. A point of the band
/// (depth below `band` element sizes, the size being the longest edge of the nearest triangle) is
/// therefore not integrated: its value is interpolated along the line from the nearest surface
/// point x0 through it, quadratically between the surface value at x0 (surface_stress.hpp,
/// interpolated over the triangle) and the integrated values at depths δ and 2δ on that line,
/// δ the band's depth. That is exact for the linear fields of a patch test and as smooth as the
/// field elsewhere. Where the line leaves the body or comes close to another part of the surface
/// (thin walls, corners), δ is halved (up to twice), then the second support point dropped
/// (linear interpolation), and only then is the point integrated where it is.
///
/// A point within `on_surface` × the surface's size of the surface takes the surface value.
#pragma once

#include "hssbem/core/option_table.hpp"
#include "hssbem/post/stress_kernels.hpp"
#include "hssbem/mesh/surface_locator.hpp"

#include <array>
#include <vector>

namespace hssbem {

struct InteriorPlanOptions {
  double band = option_default::bem_interior_band; ///< depth of the band, in element sizes; 0: no band (every inside point integrated)
  double on_surface = 1e-9; ///< points closer than this × the surface's size are on it
  /// Look for the nearest surface point first within band × the 90th percentile of the
  /// triangles' longest edges, and beyond it only among the longer triangles: the same plan as
  /// one search within band × the longest edge (false), cheaper where the edges vary.
  bool staged_search = true;
};

enum class PointKind : char { Outside, Surface, Band, Deep };

/// Per point: displacement (3) and stress (6, Voigt).
using FieldValue = std::array<double, field_outputs>;

class InteriorPlan {
public:
  /// Classify `points` (and find the support points of the band). O(points · log triangles).
  /// `inside`, if given, says for each point whether it lies inside (1) or outside (0) the body,
  /// or that the plan must find out (−1, by the winding number); 2 says that it lies inside and
  /// no surface point lies within search_reach() of it: deep, with no search (grid_inside).
  InteriorPlan(const SurfaceLocator &locator, const SurfaceMesh &mesh, const std::vector<Vec3> &points, const InteriorPlanOptions &options = {},
               const std::vector<signed char> *inside = nullptr);

  std::size_t num_points() const { return m_recipe.size(); }
  PointKind kind(std::size_t p) const { return m_recipe[p].kind; }
  /// How far from a point the plan looks for the surface: a point with no surface point this
  /// close is deep.
  static double search_reach(const SurfaceLocator &locator, const SurfaceMesh &mesh, const InteriorPlanOptions &options);
  /// The points to integrate: each deep point, and the support points of the band.
  const std::vector<Vec3> &evaluation_points() const { return m_eval; }

  /// The field at every point from `values` (field_outputs per evaluation point) and the surface
  /// fields per triangle corner; NaN outside the body.
  std::vector<FieldValue> finish(const std::vector<double> &values, const std::vector<std::array<Vec3, 3>> &corner_u,
                                 const std::vector<std::array<Voigt, 3>> &corner_stress) const;

private:
  struct Recipe {
    PointKind kind = PointKind::Outside;
    int triangle = -1;
    Vec3 bary{};
    int eval[2] = {-1, -1};
    double w_surface = 0, w[2] = {0, 0};
  };
  /// Distances of the classification: on the surface, the band's search radius, its depth in element sizes.
  struct Reach {
    double on = 0, band = 0, band_depth = 0;
  };
  /// The recipe of point x (side: 2 deep, 1 inside, 0 outside, −1 unknown), its evaluation points in
  /// `support` (eval[s] = 0 marks support[s] as used; numbered by the constructor).
  class Search; ///< the nearest surface point within the band's reach (near_surface.cpp)
  static Recipe classify(const Search &search, const SurfaceMesh &mesh, const Vec3 &x, signed char side, const Reach &reach, std::array<Vec3, 2> &support);
  static Recipe band_recipe(const SurfaceLocator &locator, const SurfaceMesh &mesh, const Vec3 &x, const SurfaceLocator::Nearest &n, double delta,
                            std::array<Vec3, 2> &support);
  static Recipe deep_recipe(const Vec3 &x, std::array<Vec3, 2> &support);

  std::vector<Recipe> m_recipe;
  std::vector<Vec3> m_eval;
};

/// Inside (1) or outside (0) for the points of a regular grid, point (i, j, k) at origin + (i, j,
/// k) * spacing, numbered x fastest: the winding number only at the points within a grid step of
/// the surface; the others take the side of a neighbour, since a segment of one step from a point
/// farther than a step from the surface cannot cross it (connected components of such steps,
/// each taking the side of one of its points whose winding number is known). The points within a
/// step of the surface are found among those within a step of some triangle's bounding box.
///
/// With `deep_beyond` > 0 (InteriorPlan::search_reach), an inside point that is surely farther
/// than that from the surface is 2 instead of 1, and the plan takes it as deep without a search:
/// a point with no point within a step of the surface (nor of the grid's boundary) within r grid
/// points along every axis lies at least (r + ½) h from the surface (h the smallest spacing: the
/// grid point nearest to its nearest surface point is within a step of the surface).
std::vector<signed char> grid_inside(const SurfaceLocator &locator, const Vec3 &origin, const Vec3 &spacing, const std::array<int, 3> &points,
                                     double deep_beyond = 0);

} // namespace hssbem
