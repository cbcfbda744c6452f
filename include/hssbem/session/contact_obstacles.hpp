/// \file contact_obstacles.hpp
/// What a contact session does with its obstacles besides solving (contact_obstacles.cxx): the
/// check that mesh obstacles face the bodies, the note on vertices beyond an open mesh's depth
/// (the driver prints it), and the obstacles' surfaces for the result file.
#pragma once

#include "hssbem/contact/obstacle.hpp"
#include "hssbem/io/hdf5_output.hpp"
#include "hssbem/problem/setup.hpp"

#include <string>
#include <vector>

namespace hssbem {

class ContactObstacles {
public:
  /// `held`: per vertex, its prescribed displacement components (a vertex held in all three is no
  /// candidate); `where`: per vertex, selected by "contact.where" (empty: every vertex); `reach`
  /// and `depth` as the contact options give them (0: automatic, as the engine takes them: the
  /// reach 5 % of the mesh's bounding-box diagonal, the depth the reach). `s` names the file in
  /// messages (none for a problem made in memory).
  ContactObstacles(const ProblemSetup &s, const std::vector<Obstacle> &obstacles, const std::vector<std::array<bool, 3>> &held, const std::vector<char> &where, double reach,
                   double depth);

  /// Throws ProblemError naming the file and the obstacle when a mesh obstacle's triangles face
  /// away from the bodies (check_obstacle_faces), judged at the first of `poses` (the session
  /// gives the base position first, then the frames') that has candidate vertices within reach
  /// of it.
  void check_facing(const std::vector<std::vector<Pose>> &poses) const;
  /// Says once per open mesh obstacle (on rank 0's standard output) when frame `frame` starts
  /// with candidate vertices deeper than the depth behind it: not in contact with it.
  void note_depth(long long frame, const std::vector<Pose> &poses);
  /// The obstacles' surfaces (obstacle_surface: a plane's patch around the bodies), at `poses`.
  std::vector<ObstacleSurface> surfaces(const std::vector<Pose> &poses) const;
  /// Each surface's vertices at `poses`: a frame's /frames/<i>/obstacles.
  std::vector<std::vector<Vec3>> placed(const std::vector<Pose> &poses) const;

private:
  const ProblemSetup &m_s;
  std::vector<ObstacleGeometry> m_geometry;
  std::vector<SurfaceMesh> m_surface; ///< at the base position
  std::vector<Vec3> m_candidates;     ///< the vertices that may touch (where, and not held in all three components)
  std::vector<Vec3> m_candidate_normals; ///< their outward unit normals
  double m_reach = 0, m_depth = 0;
  std::vector<char> m_noted;          ///< per obstacle: the depth note was said
};

} // namespace hssbem
