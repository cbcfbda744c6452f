/// \file obstacle_output.cpp
/// The obstacles' part of the result layout (see hdf5_output.hpp): each rigid obstacle's surface
/// under /obstacles/<name> (where it is, or its base position in a scene), its place in each
/// frame under /frames/<i>/obstacles/<name>/vertices, their checks and their XDMF view (a grid
/// per obstacle beside the body's, a temporal collection per obstacle in a scene).
#include "result_layout.hpp"

namespace hssbem::detail {

namespace {

std::string obstacle_group(const std::string &parent, const std::string &name) { return parent + "/obstacles/" + name; }

XdmfGrid obstacle_grid(const std::string &h5_name, const ObstacleSurface &o, const std::string &vertices)
{
  XdmfGrid g;
  g.h5_name = h5_name;
  g.name = "obstacle " + o.name;
  g.num_vertices = o.vertices.size();
  g.num_triangles = o.triangles.size();
  g.vertices = vertices;
  g.triangles = obstacle_group("", o.name) + "/triangles";
  return g;
}

} // namespace

bool link_name_ok(const std::string &name)
{
  if (name.empty() || name == "." || name == "..") return false;
  for (const char c : name)
    if (c == '/' || static_cast<unsigned char>(c) < 0x20 || c == 0x7f) return false;
  return true;
}

void write_obstacles(H5Writer &w, const std::vector<ObstacleSurface> &obstacles)
{
  if (obstacles.empty()) return;
  H5Handle top = w.group("/obstacles");
  for (const ObstacleSurface &o : obstacles) {
    const std::string name = obstacle_group("", o.name);
    H5Handle g = w.group(name);
    write_vec3s(w, g, name, "vertices", o.vertices);
    w.dataset(g.get(), name, "triangles", int32s(flatten(o.triangles), {count(o.triangles.size()), 3}));
    const std::map<std::string, double> no_real;
    const std::map<std::string, long long> no_int;
    write_attributes(w, g.get(), name, {no_real, no_int, {{"shape", o.shape}}});
    w.end_group(g, name);
  }
  w.end_group(top, "/obstacles");
}

void write_frame_obstacles(H5Writer &w, const std::string &frame, const std::vector<ObstacleSurface> &base, const std::vector<std::vector<Vec3>> &vertices)
{
  if (vertices.empty()) return;
  H5Handle top = w.group(frame + "/obstacles");
  for (std::size_t k = 0; k < base.size(); ++k) {
    const std::string name = obstacle_group(frame, base[k].name);
    H5Handle g = w.group(name);
    write_vec3s(w, g, name, "vertices", vertices[k]);
    w.end_group(g, name);
  }
  w.end_group(top, frame + "/obstacles");
}

void check_obstacles(const std::string &path, const std::vector<ObstacleSurface> &obstacles)
{
  for (std::size_t k = 0; k < obstacles.size(); ++k) {
    const ObstacleSurface &o = obstacles[k];
    if (!link_name_ok(o.name) || o.name.find(':') != std::string::npos)
      fail_output(path, "obstacle name '" + o.name + "' cannot name the group /obstacles/<name> (no '/' or ':', not '.' or '..', no control character)");
    for (std::size_t j = 0; j < k; ++j)
      if (obstacles[j].name == o.name) fail_output(path, "two obstacles are named '" + o.name + "'");
    const std::string g = obstacle_group("", o.name);
    if (o.vertices.empty() || o.triangles.empty()) fail_output(path, g + " has no surface (" + std::to_string(o.vertices.size()) + " vertices, " + std::to_string(o.triangles.size()) + " triangles)");
    for (std::size_t t = 0; t < o.triangles.size(); ++t)
      for (int v : o.triangles[t])
        if (v < 0 || static_cast<std::size_t>(v) >= o.vertices.size())
          fail_output(path, g + "/triangles row " + std::to_string(t) + " refers to vertex " + std::to_string(v) + " of " + std::to_string(o.vertices.size()));
    check_finite(path, g + "/vertices", o.vertices);
  }
}

void check_frame_obstacles(const std::string &path, const std::string &frame, const std::vector<ObstacleSurface> &base, const std::vector<std::vector<Vec3>> &vertices)
{
  if (vertices.empty()) return;
  check_size(path, frame + "/obstacles", vertices.size(), base.size(), "obstacle of the base", true);
  for (std::size_t k = 0; k < base.size(); ++k) {
    const std::string g = obstacle_group(frame, base[k].name) + "/vertices";
    check_size(path, g, vertices[k].size(), base[k].vertices.size(), "vertex of the obstacle's surface", true);
    check_finite(path, g, vertices[k]);
  }
}

std::vector<XdmfGrid> obstacle_grids(const std::string &h5_name, const std::vector<ObstacleSurface> &obstacles)
{
  std::vector<XdmfGrid> out;
  for (const ObstacleSurface &o : obstacles) out.push_back(obstacle_grid(h5_name, o, obstacle_group("", o.name) + "/vertices"));
  return out;
}

std::vector<XdmfCollection> obstacle_collections(const std::string &h5_name, const std::vector<ObstacleSurface> &obstacles, const std::vector<bool> &placed)
{
  std::vector<XdmfCollection> out;
  for (const ObstacleSurface &o : obstacles) {
    XdmfCollection c{"obstacle " + o.name, {}};
    for (std::size_t i = 0; i < placed.size(); ++i) {
      const std::string frame = "/frames/" + std::to_string(i);
      c.steps.push_back(obstacle_grid(h5_name, o, obstacle_group(placed[i] ? frame : "", o.name) + "/vertices"));
      c.steps.back().time = static_cast<double>(i);
    }
    out.push_back(std::move(c));
  }
  return out;
}

} // namespace hssbem::detail
