/// \file problem_file.cpp
/// Reading the problem file (JSON with comments) into a ProblemSpec.
///
/// Every value is checked where it is read, and every message names the file and the JSON path of
/// the value at fault (e.g. "boundary[2].where.box"). Row lists may hold 10^5 entries (the bulk
/// form a contact detector hands over), so rows are converted in tight loops straight into
/// std::vector<Vec3>; a path string is built only once something is wrong.
#include "hssbem/problem/problem.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <climits>
#include <cstdint>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <set>
#include <sstream>

namespace hssbem {
namespace {

using json = nlohmann::json;

/// Where a value sits: the file and the JSON path, for messages.
struct Where {
  const std::string &origin;
  std::string path;

  Where at(const std::string &key) const { return {origin, path.empty() ? key : path + "." + key}; }
  Where at(std::size_t i) const { return {origin, path + "[" + std::to_string(i) + "]"}; }

  [[noreturn]] void fail(const std::string &what) const
  {
    std::string msg = origin.empty() ? std::string() : origin + ": ";
    throw ProblemError(msg + (path.empty() ? "" : path + ": ") + what);
  }
};

std::string join(std::initializer_list<const char *> words)
{
  std::string s;
  for (const char *w : words)
    s += (s.empty() ? "" : ", ") + std::string(w);
  return s;
}

/// Refuses non-objects and keys outside `known`: a misspelt key would otherwise be silently ignored.
void check_keys(const json &j, const Where &w, std::initializer_list<const char *> known)
{
  if (!j.is_object())
    w.fail(std::string("expected an object, got ") + j.type_name());
  for (const auto &item : j.items()) {
    bool ok = false;
    for (const char *k : known)
      ok = ok || item.key() == k;
    if (!ok)
      w.fail("unknown key '" + item.key() + "' (known: " + join(known) + ")");
  }
}

/// A number (or null -> NaN when allowed); false for anything else. nlohmann refuses overflowing
/// literals, so a stored number is always finite.
bool try_number(const json &j, bool allow_null, double &out)
{
  if (j.is_number()) {
    out = j.get<double>();
    return std::isfinite(out);
  }
  if (allow_null && j.is_null()) {
    out = std::numeric_limits<double>::quiet_NaN();
    return true;
  }
  return false;
}

std::string number_error(const json &j, bool allow_null)
{
  if (j.is_number())
    return "non-finite number";
  return std::string(allow_null ? "expected a number or null" : "expected a number") + ", got " +
         j.type_name();
}

double read_number(const json &j, const Where &w)
{
  double x = 0;
  if (!try_number(j, false, x))
    w.fail(number_error(j, false));
  return x;
}

bool try_vec3(const json &j, bool allow_null, Vec3 &out)
{
  return j.is_array() && j.size() == 3 && try_number(j[0], allow_null, out[0]) &&
         try_number(j[1], allow_null, out[1]) && try_number(j[2], allow_null, out[2]);
}

/// Says what is wrong with a value try_vec3 refused.
[[noreturn]] void vec3_fail(const json &j, bool allow_null, const Where &w)
{
  if (!j.is_array())
    w.fail(std::string("expected a 3-vector [x, y, z], got ") + j.type_name());
  if (j.size() != 3)
    w.fail("expected 3 components, got " + std::to_string(j.size()));
  double x = 0;
  for (std::size_t c = 0; c < 3; ++c)
    if (!try_number(j[c], allow_null, x))
      w.at(c).fail(number_error(j[c], allow_null));
  w.fail("malformed 3-vector");
}

Vec3 read_vec3(const json &j, const Where &w, bool allow_null = false)
{
  Vec3 v{};
  if (!try_vec3(j, allow_null, v))
    vec3_fail(j, allow_null, w);
  return v;
}

/// A non-empty list of 3-vectors; the hot loop of the bulk form.
std::vector<Vec3> read_vec3_list(const json &j, const Where &w, bool allow_null)
{
  if (!j.is_array() || j.empty())
    w.fail("expected a non-empty list of 3-vectors [[x, y, z], ...]");
  std::vector<Vec3> rows(j.size());
  for (std::size_t i = 0; i < rows.size(); ++i)
    if (!try_vec3(j[i], allow_null, rows[i]))
      vec3_fail(j[i], allow_null, w.at(i));
  return rows;
}

/// Displacement / traction: one row [x, y, z] for the whole selection or a list of rows.
std::vector<Vec3> read_rows(const json &j, const Where &w)
{
  if (!j.is_array() || j.empty())
    w.fail("expected [x, y, z] or a list of rows [[x, y, z], ...]");
  if (j.front().is_array())
    return read_vec3_list(j, w, true);
  return {read_vec3(j, w, true)};
}

/// Pressure: one number, or a list of numbers (null leaves that vertex as it was).
std::vector<double> read_pressure(const json &j, const Where &w)
{
  if (!j.is_array())
    return {read_number(j, w)};
  if (j.empty())
    w.fail("expected a number or a non-empty list of numbers");
  std::vector<double> p(j.size());
  for (std::size_t i = 0; i < p.size(); ++i)
    if (!try_number(j[i], true, p[i]))
      w.at(i).fail(number_error(j[i], true));
  return p;
}

/// A non-negative index that fits an int; anything else is named in the message.
int read_index(const json &j, const Where &w, const char *what)
{
  if (j.is_number_unsigned() && j.get<std::uint64_t>() <= static_cast<std::uint64_t>(INT_MAX))
    return static_cast<int>(j.get<std::uint64_t>());
  if (j.is_number_unsigned())
    w.fail(std::string(what) + " " + j.dump() + " out of range");
  if (j.is_number_integer())
    w.fail(std::string(what) + " " + j.dump() + " is negative");
  w.fail(std::string("expected an integer ") + what + ", got " + j.type_name());
}

void read_region(const json &j, const Where &w, Selector &s)
{
  s.kind = Selector::Kind::Region;
  if (j.is_string()) {
    s.region_name = j.get<std::string>();
    if (s.region_name.empty())
      w.fail("empty region name");
    return;
  }
  if (!j.is_number_integer())
    w.fail(std::string("expected a region name or a physical tag, got ") + j.type_name());
  s.region_tag = read_index(j, w, "region tag");
  if (s.region_tag == 0)
    w.fail("region tag 0 is not a Gmsh physical tag (tags start at 1)");
}

void read_box(const json &j, const Where &w, Selector &s)
{
  if (!j.is_array() || j.size() != 2)
    w.fail("expected [[xlo, ylo, zlo], [xhi, yhi, zhi]]");
  s.kind = Selector::Kind::Box;
  s.lo = read_vec3(j[0], w.at(0));
  s.hi = read_vec3(j[1], w.at(1));
  for (int c = 0; c < 3; ++c)
    if (s.lo[c] > s.hi[c])
      w.fail("lower corner exceeds upper corner in component " + std::to_string(c));
}

void read_sphere(const json &j, const Where &w, Selector &s)
{
  check_keys(j, w, {"center", "radius"});
  if (!j.contains("center") || !j.contains("radius"))
    w.fail("expected {\"center\": [x, y, z], \"radius\": r}");
  s.kind = Selector::Kind::Sphere;
  s.center = read_vec3(j["center"], w.at("center"));
  s.radius = read_number(j["radius"], w.at("radius"));
  if (s.radius < 0)
    w.at("radius").fail("radius must not be negative");
}

void read_vertex_list(const json &j, const Where &w, Selector &s)
{
  if (!j.is_array() || j.empty())
    w.fail("expected a non-empty list of vertex indices (0-based)");
  s.kind = Selector::Kind::Vertices;
  s.vertices.resize(j.size());
  for (std::size_t i = 0; i < j.size(); ++i)
    s.vertices[i] = read_index(j[i], w.at(i), "vertex index");
}

Selector read_selector(const json &j, const Where &w)
{
  Selector s;
  if (j.is_string() && j.get<std::string>() == "all")
    return s;
  if (j.is_string())
    w.fail("unknown selector '" + j.get<std::string>() + "' (expected \"all\" or an object)");
  check_keys(j, w, {"region", "box", "sphere", "vertices"});
  if (j.size() != 1)
    w.fail("expected exactly one of region, box, sphere, vertices; got " + std::to_string(j.size()));
  const auto item = j.items().begin();
  const Where wk = w.at(item.key());
  if (item.key() == "region")
    read_region(item.value(), wk, s);
  else if (item.key() == "box")
    read_box(item.value(), wk, s);
  else if (item.key() == "sphere")
    read_sphere(item.value(), wk, s);
  else
    read_vertex_list(item.value(), wk, s);
  return s;
}

/// Values whose magnitude the solve can carry: with lengths and moduli within 1e±30 as well
/// (mesh and material checks), every entry and product of the system stays a normal double.
constexpr double k_max_value = 1e30;

void check_magnitude(double x, const Where &w)
{
  if (std::abs(x) > k_max_value) {
    std::ostringstream msg;
    msg << "value " << x << " exceeds " << k_max_value << " in magnitude, where the solve overflows double precision; rescale the units";
    w.fail(msg.str());
  }
}

void check_magnitudes(const BoundaryRule &rule, const Where &w)
{
  for (std::size_t i = 0; i < rule.pressure.size(); ++i) check_magnitude(rule.pressure[i], w);
  for (std::size_t i = 0; i < rule.rows.size(); ++i)
    for (double x : rule.rows[i]) check_magnitude(x, w);
}

BoundaryRule read_rule(const json &j, const Where &w)
{
  check_keys(j, w, {"where", "displacement", "traction", "pressure"});
  if (!j.contains("where"))
    w.fail("missing 'where' (a selector: \"all\", region, box, sphere or vertices)");
  const int n = int(j.contains("displacement")) + int(j.contains("traction")) + int(j.contains("pressure"));
  if (n != 1)
    w.fail(std::string(n == 0 ? "needs" : "has more than") +
           " one of 'displacement', 'traction', 'pressure' (give exactly one per rule)");
  BoundaryRule rule;
  rule.where = read_selector(j["where"], w.at("where"));
  if (j.contains("pressure")) {
    rule.kind = BoundaryRule::Kind::Pressure;
    rule.pressure = read_pressure(j["pressure"], w.at("pressure"));
    check_magnitudes(rule, w.at("pressure"));
    return rule;
  }
  const bool disp = j.contains("displacement");
  rule.kind = disp ? BoundaryRule::Kind::Displacement : BoundaryRule::Kind::Traction;
  const char *key = disp ? "displacement" : "traction";
  rule.rows = read_rows(j[key], w.at(key));
  check_magnitudes(rule, w.at(key));
  return rule;
}

std::optional<double> optional_number(const json &j, const char *key, const Where &w)
{
  if (!j.contains(key))
    return std::nullopt;
  return read_number(j[key], w.at(key));
}

/// Keeps the values as given: the driver validates them after command-line overrides.
void read_material(const json &j, const Where &w, ProblemSpec &spec)
{
  check_keys(j, w, {"E", "nu", "lambda", "mu", "density"});
  spec.density = optional_number(j, "density", w);
  if (spec.density && *spec.density < 0)
    w.at("density").fail("the density must be >= 0 (mass per volume), got " + j["density"].dump());
  if (spec.density)
    check_magnitude(*spec.density, w.at("density"));
  spec.E = optional_number(j, "E", w);
  spec.nu = optional_number(j, "nu", w);
  spec.lambda = optional_number(j, "lambda", w);
  spec.mu = optional_number(j, "mu", w);
  const bool young = spec.E || spec.nu, lame = spec.lambda || spec.mu;
  if (young && lame)
    w.fail("give either E and nu or lambda and mu, not both");
  if (!young && !lame)
    w.fail("expected {\"E\": .., \"nu\": ..} or {\"lambda\": .., \"mu\": ..}");
  if (young && !(spec.E && spec.nu))
    w.fail(spec.E ? "'E' given without 'nu'" : "'nu' given without 'E'");
  if (lame && !(spec.lambda && spec.mu))
    w.fail(spec.lambda ? "'lambda' given without 'mu'" : "'mu' given without 'lambda'");
}

std::string read_string(const json &j, const Where &w)
{
  if (!j.is_string() || j.get<std::string>().empty())
    w.fail(std::string("expected a non-empty string, got ") + (j.is_string() ? "\"\"" : j.type_name()));
  return j.get<std::string>();
}

/// Relative mesh paths are meant relative to the problem file, not to the run's cwd.
std::string resolve_mesh_path(const std::string &mesh, const std::string &origin)
{
  const std::filesystem::path p(mesh);
  if (p.is_absolute())
    return mesh;
  return (std::filesystem::path(origin).parent_path() / p).string();
}

/// nlohmann keeps only the last of duplicate keys, so a second "boundary" would silently drop the
/// first one's rules: refuse duplicates while parsing.
json::parser_callback_t duplicate_key_guard(std::vector<std::set<std::string>> &open, const Where &w)
{
  return [&open, &w](int, json::parse_event_t event, json &parsed) {
    if (event == json::parse_event_t::object_start)
      open.emplace_back();
    else if (event == json::parse_event_t::object_end)
      open.pop_back();
    else if (event == json::parse_event_t::key && !open.back().insert(parsed.get<std::string>()).second)
      w.fail("duplicate key '" + parsed.get<std::string>() + "'");
    return true;
  };
}

/// nlohmann's message without its "[json.exception.parse_error.101] " tag.
std::string untagged(const json::exception &e)
{
  const std::string what = e.what();
  const auto tag_end = what.find("] ");
  return tag_end == std::string::npos ? what : what.substr(tag_end + 2);
}

json parse_json(const std::string &text, const Where &w)
{
  std::vector<std::set<std::string>> open;
  try {
    return json::parse(text, duplicate_key_guard(open, w), true, /*ignore_comments=*/true);
  } catch (const json::parse_error &e) {
    w.fail("malformed JSON (byte " + std::to_string(e.byte) + "): " + untagged(e));
  } catch (const json::out_of_range &e) { // 1e999 overflows to infinity
    w.fail("malformed JSON: " + untagged(e) + " (numbers must be finite)");
  } catch (const json::exception &e) {
    w.fail("malformed JSON: " + untagged(e));
  }
}

/// A count of cells: an integer from 1 to max.
int read_cells(const json &j, const Where &w)
{
  if (!j.is_number_integer())
    w.fail(std::string("expected a whole number of cells, got ") + (j.is_number() ? j.dump() : j.type_name()));
  if (j.is_number_unsigned() && j.get<std::uint64_t>() >= 1 && j.get<std::uint64_t>() <= 100000)
    return static_cast<int>(j.get<std::uint64_t>());
  w.fail("the number of cells must lie between 1 and 100000, got " + j.dump());
}

InteriorGrid read_grid(const json &j, const Where &w)
{
  check_keys(j, w, {"box", "cells"});
  if (!j.contains("box") || !j.contains("cells"))
    w.fail("expected {\"box\": [[xlo, ylo, zlo], [xhi, yhi, zhi]], \"cells\": [nx, ny, nz]}");
  InteriorGrid g;
  const json &box = j["box"], &cells = j["cells"];
  if (!box.is_array() || box.size() != 2)
    w.at("box").fail("expected [[xlo, ylo, zlo], [xhi, yhi, zhi]]");
  g.lo = read_vec3(box[0], w.at("box").at(0));
  g.hi = read_vec3(box[1], w.at("box").at(1));
  for (int c = 0; c < 3; ++c)
    if (!(g.lo[c] < g.hi[c]))
      w.at("box").fail("the upper corner must exceed the lower corner in every component (component " + std::to_string(c) + ": " + box[0][c].dump() + " to " +
                       box[1][c].dump() + ")");
  if (!cells.is_array() || cells.size() != 3)
    w.at("cells").fail("expected [nx, ny, nz], the number of cells along x, y and z");
  for (std::size_t c = 0; c < 3; ++c) g.cells[c] = read_cells(cells[c], w.at("cells").at(c));
  if (g.num_points() > max_grid_points)
    w.fail("the grid has " + std::to_string(g.num_points()) + " points, more than " + std::to_string(max_grid_points));
  return g;
}

/// "interior_points": a list of points, or {"points": [...], "grid": {...}} (either or both).
void read_interior_points(const json &j, const Where &w, ProblemSpec &spec)
{
  if (j.is_array()) {
    if (!j.empty())
      spec.interior_points = read_vec3_list(j, w, false);
    return;
  }
  check_keys(j, w, {"points", "grid"});
  if (j.empty())
    w.fail("expected a list of points [[x, y, z], ...] or {\"grid\": {...}} with or without \"points\"");
  if (j.contains("points"))
    spec.interior_points = read_vec3_list(j["points"], w.at("points"), false);
  if (j.contains("grid"))
    spec.interior_grid = read_grid(j["grid"], w.at("grid"));
}

/// "gravity": [gx, gy, gz], an acceleration (the body force per volume is density × gravity).
Vec3 read_gravity(const json &j, const Where &w)
{
  const Vec3 g = read_vec3(j, w);
  for (int c = 0; c < 3; ++c) check_magnitude(g[c], w.at(c));
  return g;
}

/// Gravity, at the top or in a frame, needs the material's density, and density × |gravity| must
/// stay within the values' bound.
void check_gravity_density(const ProblemSpec &spec, const Where &top)
{
  const auto weight_fits = [&](const std::optional<Vec3> &g, const Where &w) { // the body force too stays a value the solve can carry
    if (g && spec.density) check_magnitude(*spec.density * norm(*g), w);
  };
  weight_fits(spec.gravity, top.at("gravity"));
  for (std::size_t f = 0; f < spec.frames.size(); ++f) weight_fits(spec.frames[f].gravity, top.at("frames").at(f).at("gravity"));
  if (spec.density) return;
  const auto needs = [&](const Where &w) { w.fail("gravity needs the material's 'density' (mass per volume: \"material\": {\"E\": .., \"nu\": .., \"density\": ..})"); };
  if (spec.gravity) needs(top.at("gravity"));
  for (std::size_t f = 0; f < spec.frames.size(); ++f)
    if (spec.frames[f].gravity) needs(top.at("frames").at(f).at("gravity"));
}

void read_top_level(const json &j, const Where &w, ProblemSpec &spec)
{
  check_keys(j, w, {"mesh", "material", "boundary", "frames", "interior_points", "output", "contact", "gravity"});
  if (!j.contains("mesh"))
    w.fail("missing 'mesh' (path of the surface mesh, relative to the problem file)");
  if (!j.contains("material"))
    w.fail("missing 'material' ({\"E\": .., \"nu\": ..} or {\"lambda\": .., \"mu\": ..})");
  spec.mesh_path = resolve_mesh_path(read_string(j["mesh"], w.at("mesh")), spec.file);
  read_material(j["material"], w.at("material"), spec);
  if (j.contains("output"))
    spec.output = read_string(j["output"], w.at("output"));
  if (j.contains("gravity"))
    spec.gravity = read_gravity(j["gravity"], w.at("gravity"));
  if (j.contains("interior_points"))
    read_interior_points(j["interior_points"], w.at("interior_points"), spec);
}

/// A "boundary" list, the base one or a frame's: the same grammar for both.
std::vector<BoundaryRule> read_rule_list(const json &j, const Where &w)
{
  if (!j.is_array())
    w.fail(std::string("expected a list of rules, got ") + j.type_name());
  std::vector<BoundaryRule> rules;
  rules.reserve(j.size());
  for (std::size_t i = 0; i < j.size(); ++i)
    rules.push_back(read_rule(j[i], w.at(i)));
  return rules;
}

/// A frame's "rotate": {"axis": [ax, ay, az], "angle": degrees, "about": [cx, cy, cz]}.
ObstacleTurn read_turn(const json &j, const Where &w)
{
  check_keys(j, w, {"axis", "angle", "about"});
  if (!j.contains("axis") || !j.contains("angle"))
    w.fail("missing 'axis' or 'angle' (a turn by 'angle' degrees about 'axis', through 'about' or the obstacle's default centre)");
  ObstacleTurn t;
  t.axis = read_vec3(j["axis"], w.at("axis"));
  if (norm(t.axis) == 0)
    w.at("axis").fail("the rotation axis is zero");
  t.angle_deg = read_number(j["angle"], w.at("angle"));
  if (j.contains("about"))
    t.about = read_vec3(j["about"], w.at("about"));
  return t;
}

/// A frame's "obstacles": {"name": {"translate": [dx, dy, dz], "rotate": {...}}, ...}; the names
/// are checked against "contact.obstacles" once the whole file is read (check_frame_obstacles).
void read_frame_obstacles(const json &j, const Where &w, FrameSpec &f)
{
  if (!j.is_object())
    w.fail(std::string("expected {\"<obstacle name>\": {\"translate\": [dx, dy, dz], \"rotate\": {...}}, ...}, got ") + j.type_name());
  for (const auto &item : j.items()) {
    const Where wi = w.at(item.key());
    check_keys(item.value(), wi, {"translate", "rotate"});
    if (!item.value().contains("translate") && !item.value().contains("rotate"))
      wi.fail("missing 'translate' or 'rotate' (the obstacle's place relative to its base position in this frame)");
    const Vec3 t = item.value().contains("translate") ? read_vec3(item.value()["translate"], wi.at("translate")) : Vec3{0, 0, 0};
    f.obstacles.emplace_back(item.key(), t);
    if (item.value().contains("rotate"))
      f.turns[item.key()] = read_turn(item.value()["rotate"], wi.at("rotate"));
  }
}

FrameSpec read_frame(const json &j, const Where &w)
{
  check_keys(j, w, {"boundary", "obstacles", "gravity"});
  if (!j.contains("boundary") && !j.contains("obstacles") && !j.contains("gravity"))
    w.fail("missing 'boundary' (the frame's rules, applied after the base rules; may be []), 'obstacles' or 'gravity'");
  FrameSpec f;
  if (j.contains("gravity"))
    f.gravity = read_gravity(j["gravity"], w.at("gravity"));
  if (j.contains("boundary"))
    f.rules = read_rule_list(j["boundary"], w.at("boundary"));
  if (j.contains("obstacles"))
    read_frame_obstacles(j["obstacles"], w.at("obstacles"), f);
  return f;
}

// --- "contact" ----------------------------------------------------------------------------------

double read_friction(const json &j, const Where &w)
{
  const double mu = read_number(j, w);
  if (mu < 0)
    w.fail("the friction coefficient must be >= 0 (0: frictionless), got " + j.dump());
  return mu;
}

void read_plane(const json &j, const Where &w, Obstacle &o)
{
  check_keys(j, w, {"point", "normal"});
  if (!j.contains("point") || !j.contains("normal"))
    w.fail("expected {\"point\": [x, y, z], \"normal\": [nx, ny, nz]} (the normal points toward the bodies)");
  o.shape = Obstacle::Shape::Plane;
  o.point = read_vec3(j["point"], w.at("point"));
  o.normal = read_vec3(j["normal"], w.at("normal"));
  if (norm(o.normal) == 0)
    w.at("normal").fail("the normal is zero");
}

void read_obstacle_sphere(const json &j, const Where &w, Obstacle &o)
{
  check_keys(j, w, {"center", "radius"});
  if (!j.contains("center") || !j.contains("radius"))
    w.fail("expected {\"center\": [x, y, z], \"radius\": r}");
  o.shape = Obstacle::Shape::Sphere;
  o.center = read_vec3(j["center"], w.at("center"));
  o.radius = read_number(j["radius"], w.at("radius"));
  if (!(o.radius > 0))
    w.at("radius").fail("the radius must be > 0, got " + j["radius"].dump());
}

/// An obstacle's name names HDF5 objects (/contact/forces/<name>, /obstacles/<name>): no '/'
/// (it would nest), not "." or ".." (the group itself, its parent), no control character.
std::string read_obstacle_name(const json &j, const Where &w)
{
  const std::string name = read_string(j, w);
  if (name == "." || name == "..")
    w.fail("the name '" + name + "' cannot name the result's datasets (/contact/forces/<name>, /obstacles/<name>)");
  for (const char c : name)
    if (c == '/' || static_cast<unsigned char>(c) < 0x20 || c == 0x7f)
      w.fail(std::string("the name ") + j.dump() + " cannot name the result's datasets (/contact/forces/<name>, /obstacles/<name>): it holds " +
             (c == '/' ? "'/'" : "a control character"));
  return name;
}

Obstacle read_obstacle(const json &j, const Where &w, const std::string &origin)
{
  check_keys(j, w, {"name", "plane", "sphere", "mesh", "friction"});
  if (!j.contains("name"))
    w.fail("missing 'name' (frames move an obstacle by its name)");
  Obstacle o;
  o.name = read_obstacle_name(j["name"], w.at("name"));
  const int shapes = int(j.contains("plane")) + int(j.contains("sphere")) + int(j.contains("mesh"));
  if (shapes != 1)
    w.fail(std::string(shapes == 0 ? "needs" : "has more than") + " one of 'plane', 'sphere', 'mesh' (give exactly one)");
  if (j.contains("plane"))
    read_plane(j["plane"], w.at("plane"), o);
  else if (j.contains("sphere"))
    read_obstacle_sphere(j["sphere"], w.at("sphere"), o);
  else {
    o.shape = Obstacle::Shape::Mesh;
    o.mesh_path = resolve_mesh_path(read_string(j["mesh"], w.at("mesh")), origin);
  }
  if (j.contains("friction"))
    o.friction = read_friction(j["friction"], w.at("friction"));
  return o;
}

std::vector<Obstacle> read_obstacles(const json &j, const Where &w, const std::string &origin)
{
  if (!j.is_array())
    w.fail(std::string("expected a list of obstacles, got ") + j.type_name());
  std::vector<Obstacle> list;
  for (std::size_t i = 0; i < j.size(); ++i) {
    list.push_back(read_obstacle(j[i], w.at(i), origin));
    for (std::size_t k = 0; k + 1 < list.size(); ++k)
      if (list[k].name == list.back().name)
        w.at(i).at("name").fail("duplicate obstacle name '" + list.back().name + "' (also " + w.at(k).path + ")");
  }
  return list;
}

/// With "bodies", /contact/forces/body_<k> holds body k's force: an obstacle of that form of
/// name would share (and lose) its dataset.
void check_body_force_names(const ContactSpec &c, const Where &w)
{
  for (std::size_t i = 0; i < c.obstacles.size(); ++i) {
    const std::string &name = c.obstacles[i].name;
    if (name.size() > 5 && name.compare(0, 5, "body_") == 0 && std::all_of(name.begin() + 5, name.end(), [](char ch) { return ch >= '0' && ch <= '9'; }))
      w.at("obstacles").at(i).at("name").fail("the name '" + name + "' is that of a body's force in the result (/contact/forces/body_<k>, with \"bodies\": true); rename the obstacle");
  }
}

ContactSpec read_contact(const json &j, const Where &w, const std::string &origin)
{
  check_keys(j, w, {"obstacles", "friction", "bodies", "where"});
  ContactSpec c;
  c.present = true;
  if (j.contains("obstacles"))
    c.obstacles = read_obstacles(j["obstacles"], w.at("obstacles"), origin);
  if (j.contains("friction"))
    c.friction = read_friction(j["friction"], w.at("friction"));
  if (j.contains("bodies")) {
    if (!j["bodies"].is_boolean())
      w.at("bodies").fail(std::string("expected true or false, got ") + j["bodies"].type_name());
    c.bodies = j["bodies"].get<bool>();
  }
  if (j.contains("where"))
    c.where = read_selector(j["where"], w.at("where"));
  if (c.bodies)
    check_body_force_names(c, w);
  return c;
}

/// Every frame's obstacles must name an obstacle of "contact": checked before any frame is solved.
void check_frame_obstacles(const ProblemSpec &spec, const Where &top)
{
  std::string known;
  for (const Obstacle &o : spec.contact.obstacles)
    known += (known.empty() ? "" : ", ") + o.name;
  for (std::size_t f = 0; f < spec.frames.size(); ++f)
    for (const auto &entry : spec.frames[f].obstacles) {
      const std::string &name  = entry.first; // not a structured binding: clang 14 (the fuzzers' compiler) cannot capture one
      const bool         found = std::any_of(spec.contact.obstacles.begin(), spec.contact.obstacles.end(), [&](const Obstacle &o) { return o.name == name; });
      if (!found)
        top.at("frames").at(f).at("obstacles").fail("no obstacle named '" + name + "' (" + (known.empty() ? "the problem has no contact obstacles" : "known: " + known) + ")");
    }
}

/// A scene: each frame is solved with the base rules followed by its own.
std::vector<FrameSpec> read_frames(const json &j, const Where &w)
{
  if (!j.is_array() || j.empty())
    w.fail(std::string("expected a non-empty list of frames [{\"boundary\": [...]}, ...], got ") +
           (j.is_array() ? "[]" : j.type_name()));
  std::vector<FrameSpec> frames;
  frames.reserve(j.size());
  for (std::size_t i = 0; i < j.size(); ++i)
    frames.push_back(read_frame(j[i], w.at(i)));
  return frames;
}

} // namespace

ProblemSpec parse_problem(const std::string &json_text, const std::string &origin)
{
  ProblemSpec spec;
  spec.file = origin;
  const Where top{spec.file, ""};
  const json j = parse_json(json_text, top);
  read_top_level(j, top, spec);
  if (j.contains("boundary"))
    spec.rules = read_rule_list(j["boundary"], top.at("boundary"));
  if (j.contains("frames"))
    spec.frames = read_frames(j["frames"], top.at("frames"));
  if (j.contains("contact"))
    spec.contact = read_contact(j["contact"], top.at("contact"), spec.file);
  check_frame_obstacles(spec, top);
  check_gravity_density(spec, top);
  return spec;
}

ProblemSpec parse_frame(const ProblemSpec &spec, const std::string &json_text, const std::string &what)
{
  ProblemSpec out = spec;
  const Where top{out.file, ""};
  const json j = parse_json(json_text, top);
  out.frames = {read_frame(j, top.at(what))};
  check_frame_obstacles(out, top);
  return out;
}

std::vector<Vec3> InteriorGrid::points() const
{
  const auto n = points_per_axis();
  const Vec3 h = spacing();
  std::vector<Vec3> p;
  p.reserve(static_cast<std::size_t>(num_points()));
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i) p.push_back({lo[0] + i * h[0], lo[1] + j * h[1], lo[2] + k * h[2]});
  return p;
}

ProblemSpec read_problem(const std::string &path)
{
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw ProblemError("cannot open problem file '" + path + "'");
  std::error_code ec; // a directory opens fine and then reads as an empty, "malformed" file
  if (std::filesystem::is_directory(path, ec))
    throw ProblemError("cannot open problem file '" + path + "': is a directory");
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad())
    throw ProblemError("cannot read problem file '" + path + "'");
  return parse_problem(text.str(), path);
}

} // namespace hssbem
