/// \file triangle_crossing.cpp
/// The triangle–triangle test of the intersection check (see triangle_crossing.hpp): Möller's
/// interval test (J. Graphics Tools 2, 1997) made strict, and a 2D overlap test for triangles in
/// one plane.
#include "triangle_crossing.hpp"

#include <algorithm>
#include <cmath>

namespace hssbem::detail {

namespace {

/// Signed distances of b's corners to the plane of a (unit normal n through a[0]), those within
/// eps set to zero.
std::array<double, 3> plane_distances(const Vec3 &n, const Vec3 &origin, const Triangle &b, double eps)
{
  std::array<double, 3> d{};
  for (int i = 0; i < 3; ++i) {
    d[i] = dot(n, b[i] - origin);
    if (std::abs(d[i]) <= eps) d[i] = 0;
  }
  return d;
}

bool straddles(const std::array<double, 3> &d)
{
  return *std::max_element(d.begin(), d.end()) > 0 && *std::min_element(d.begin(), d.end()) < 0;
}

/// The interval that the segment where `t` meets the other plane (distances d, t straddling it)
/// covers along the unit direction `dir`.
std::array<double, 2> interval(const Triangle &t, const std::array<double, 3> &d, const Vec3 &dir)
{
  double lo = HUGE_VAL, hi = -HUGE_VAL;
  auto   take = [&](const Vec3 &p) {
    const double s = dot(dir, p);
    lo             = std::min(lo, s);
    hi             = std::max(hi, s);
  };
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3;
    if (d[i] == 0) take(t[i]);
    if ((d[i] < 0 && d[j] > 0) || (d[i] > 0 && d[j] < 0)) take(t[i] + (d[i] / (d[i] - d[j])) * (t[j] - t[i]));
  }
  return {lo, hi};
}

// --- triangles in one plane, projected onto the two coordinates the normal is least along ----

using Point = std::array<double, 2>;

/// Twice the signed area of (p, q, r) over |q − p|: the distance of r from the line pq, signed.
double side(const Point &p, const Point &q, const Point &r)
{
  const double ex = q[0] - p[0], ey = q[1] - p[1], len = std::hypot(ex, ey);
  return len > 0 ? (ex * (r[1] - p[1]) - ey * (r[0] - p[0])) / len : 0.0;
}

bool segments_cross(const Point &p, const Point &q, const Point &r, const Point &s, double eps)
{
  const double a = side(p, q, r), b = side(p, q, s), c = side(r, s, p), d = side(r, s, q);
  return ((a > eps && b < -eps) || (a < -eps && b > eps)) && ((c > eps && d < -eps) || (c < -eps && d > eps));
}

bool strictly_inside(const std::array<Point, 3> &t, const Point &p, double eps)
{
  const double orient = side(t[0], t[1], t[2]) > 0 ? 1.0 : -1.0;
  for (int i = 0; i < 3; ++i)
    if (orient * side(t[i], t[(i + 1) % 3], p) <= eps) return false;
  return true;
}

std::array<Point, 3> project(const Triangle &t, int drop)
{
  const int            u = (drop + 1) % 3, v = (drop + 2) % 3;
  std::array<Point, 3> p;
  for (int i = 0; i < 3; ++i) p[i] = {t[i][u], t[i][v]};
  return p;
}

Point centroid(const std::array<Point, 3> &t) { return {(t[0][0] + t[1][0] + t[2][0]) / 3, (t[0][1] + t[1][1] + t[2][1]) / 3}; }

/// Triangles in one plane (normal n): they overlap with positive area when two edges cross
/// properly or the centroid of one lies strictly inside the other (containment, coincidence).
bool coplanar_overlap(const Triangle &a, const Triangle &b, const Vec3 &n, double eps)
{
  int drop = 0;
  for (int k = 1; k < 3; ++k)
    if (std::abs(n[k]) > std::abs(n[drop])) drop = k;
  const std::array<Point, 3> pa = project(a, drop), pb = project(b, drop);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (segments_cross(pa[i], pa[(i + 1) % 3], pb[j], pb[(j + 1) % 3], eps)) return true;
  return strictly_inside(pb, centroid(pa), eps) || strictly_inside(pa, centroid(pb), eps);
}

} // namespace

bool triangles_cross(const Triangle &a, const Triangle &b, double eps)
{
  const Vec3 ca = cross(a[1] - a[0], a[2] - a[0]), cb = cross(b[1] - b[0], b[2] - b[0]);
  const double la = norm(ca), lb = norm(cb);
  if (!(la > 0) || !(lb > 0)) return false;
  const Vec3                  na = (1.0 / la) * ca, nb = (1.0 / lb) * cb;
  const std::array<double, 3> db = plane_distances(na, a[0], b, eps); // b's corners against a's plane
  const std::array<double, 3> da = plane_distances(nb, b[0], a, eps);
  if (db == std::array<double, 3>{} || da == std::array<double, 3>{}) return dot(na, nb) > 0 && coplanar_overlap(a, b, na, eps);
  if (!straddles(da) || !straddles(db)) return false; // apart, or only touching the other's plane
  const Vec3   line = cross(na, nb);
  const double sine = norm(line);
  if (sine < 1e-12) return dot(na, nb) > 0 && coplanar_overlap(a, b, na, eps); // planes too close to parallel for a line
  const Vec3                  dir = (1.0 / sine) * line;
  const std::array<double, 2> ia = interval(a, da, dir), ib = interval(b, db, dir);
  return std::min(ia[1], ib[1]) - std::max(ia[0], ib[0]) > eps;
}

} // namespace hssbem::detail
