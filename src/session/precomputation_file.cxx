// A contact's precomputation to a file and back (see precomputation_file.hpp).
#include "hssbem/session/precomputation_file.hpp"

#include "hssbem/contact/bodies.hpp"
#include "hssbem/core/timer.hpp"
#include "hssbem/io/saved_file.hpp"
#include "hssbem/reference/composite_reference.hpp"

#include <cinttypes>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>

namespace hssbem {

namespace {

constexpr const char *kKind = "contact precomputation";
constexpr const char *kSceneKind = "scene precomputation";

std::string real_text(double v)
{
  char b[32];
  std::snprintf(b, sizeof b, "%.17g", v);
  return b;
}

std::string hash_text(std::uint64_t v)
{
  char b[24];
  std::snprintf(b, sizeof b, "%016" PRIx64, v);
  return b;
}

} // namespace

/// The Fingerprint's fields as text attributes `fingerprint_<field>`.
void write_fingerprint(SavedFileWriter &w, const Fingerprint &f)
{
  const std::pair<const char *, std::string> fields[] = {
      {"version", f.version},
      {"vertices", std::to_string(f.vertices)},
      {"triangles", std::to_string(f.triangles)},
      {"nodes", std::to_string(f.nodes)},
      {"mesh", hash_text(f.mesh)},
      {"feature_angle", real_text(f.feature_angle)},
      {"E", real_text(f.E)},
      {"nu", real_text(f.nu)},
      {"unknowns", std::to_string(f.unknowns)},
      {"pattern", hash_text(f.pattern)},
      {"candidates", std::to_string(f.candidates)},
      {"candidate_set", hash_text(f.candidate_set)},
      {"options", f.options},
      {"ranks", std::to_string(f.ranks)},
  };
  for (const auto &[name, value] : fields) w.text(std::string("fingerprint_") + name, value);
}

namespace {

/// Reads attribute `fingerprint_<name>` as a number of the kind of `out` (the whole text).
class FingerprintReader {
public:
  explicit FingerprintReader(const SavedFileReader &r) : m_r(r) {}
  std::string text(const char *name) const { return m_r.text(std::string("fingerprint_") + name); }
  void get(const char *name, long long &out) const { out = parse<long long>(name, [](const char *s, char **e) { return std::strtoll(s, e, 10); }); }
  void get(const char *name, int &out) const { out = static_cast<int>(parse<long long>(name, [](const char *s, char **e) { return std::strtoll(s, e, 10); })); }
  void get(const char *name, double &out) const { out = parse<double>(name, [](const char *s, char **e) { return std::strtod(s, e); }); }
  void get(const char *name, std::uint64_t &out) const { out = parse<std::uint64_t>(name, [](const char *s, char **e) { return std::strtoull(s, e, 16); }); }

private:
  template <class T, class F> T parse(const char *name, F convert) const
  {
    const std::string s = text(name);
    char *end = nullptr;
    const T v = static_cast<T>(convert(s.c_str(), &end));
    if (s.empty() || end != s.c_str() + s.size()) m_r.fail("its fingerprint's " + std::string(name) + " is damaged");
    return v;
  }
  const SavedFileReader &m_r;
};

} // namespace

Fingerprint read_fingerprint(const SavedFileReader &r)
{
  const FingerprintReader f(r);
  Fingerprint out;
  out.version = f.text("version");
  out.options = f.text("options");
  f.get("vertices", out.vertices), f.get("triangles", out.triangles), f.get("nodes", out.nodes), f.get("mesh", out.mesh);
  f.get("feature_angle", out.feature_angle), f.get("E", out.E), f.get("nu", out.nu), f.get("unknowns", out.unknowns);
  f.get("pattern", out.pattern), f.get("candidates", out.candidates), f.get("candidate_set", out.candidate_set), f.get("ranks", out.ranks);
  return out;
}

namespace {

// --- the dense references and the columns ---------------------------------------------------

void write_dense(SavedFileWriter &w, const std::string &at, const DenseReference &ref)
{
  const DenseReferenceData &d = ref.data();
  w.chars(at + "/pattern", d.pattern.data(), d.pattern.size());
  w.doubles(at + "/lu", d.lu.data(), d.lu.size());
  for (const auto &[name, v] : {std::make_pair("K", &d.K), std::make_pair("H", &d.H), std::make_pair("G", &d.G), std::make_pair("Gn", &d.Gn)})
    w.doubles(at + "/" + name, v->data(), v->size());
  w.ints(at + "/piv", d.piv.data(), d.piv.size());
  w.ints(at + "/kpos", d.kpos.data(), d.kpos.size());
  w.doubles(at + "/scale_t", &d.scale_t, 1);
}

std::unique_ptr<DenseReference> read_dense(const SavedFileReader &r, const std::string &at)
{
  DenseReferenceData d;
  d.pattern = r.chars(at + "/pattern");
  const std::size_t n = d.pattern.size();
  if (n == 0 || r.size(at + "/lu") != n * n) r.fail("its reference '" + at + "' is damaged (the factors do not fit its pattern)");
  d.lu.resize(n * n); // read in place: no copy of the largest array
  r.doubles(at + "/lu", d.lu.data(), d.lu.size());
  d.K = r.doubles(at + "/K"), d.H = r.doubles(at + "/H"), d.G = r.doubles(at + "/G"), d.Gn = r.doubles(at + "/Gn");
  d.piv = r.ints(at + "/piv"), d.kpos = r.ints(at + "/kpos");
  const std::vector<double> scale = r.doubles(at + "/scale_t");
  if (scale.size() != 1) r.fail("its reference '" + at + "' is damaged (scale_t)");
  d.scale_t = scale[0];
  try {
    return std::make_unique<DenseReference>(std::move(d));
  } catch (const std::invalid_argument &e) {
    r.fail(std::string("its reference '") + at + "' is damaged: " + e.what());
  }
}

void write_columns(SavedFileWriter &w, const ReferenceColumns &c)
{
  const std::size_t n = static_cast<std::size_t>(c.reference().num_unknowns());
  w.ints("columns/order", c.row_order().data(), c.row_order().size());
  const std::vector<ReferenceColumns::Block> blocks = c.blocks();
  w.text("columns_blocks", std::to_string(blocks.size()));
  for (std::size_t k = 0; k < blocks.size(); ++k) {
    const std::string at = "columns/" + std::to_string(k);
    w.ints(at + "/js", blocks[k].js.data(), blocks[k].js.size());
    w.doubles(at + "/values", blocks[k].data, n * blocks[k].js.size());
  }
}

std::shared_ptr<ReferenceColumns> read_columns(const SavedFileReader &r, const ReferenceFactorization &ref)
{
  const std::size_t n = static_cast<std::size_t>(ref.num_unknowns());
  const std::string count = r.text("columns_blocks");
  char *end = nullptr;
  const long long blocks = std::strtoll(count.c_str(), &end, 10);
  if (count.empty() || end != count.c_str() + count.size() || blocks < 0) r.fail("its columns are damaged (columns_blocks)");
  try {
    auto columns = std::make_shared<ReferenceColumns>(ref, r.ints("columns/order"));
    for (long long k = 0; k < blocks; ++k) {
      const std::string at = "columns/" + std::to_string(k);
      std::vector<int> js = r.ints(at + "/js");
      std::unique_ptr<double[]> values(new double[n * js.size()]);
      r.doubles(at + "/values", values.get(), n * js.size());
      columns->adopt(std::move(js), std::move(values));
    }
    return columns;
  } catch (const std::invalid_argument &e) {
    r.fail(std::string("its columns are damaged: ") + e.what());
  }
}

/// The loaded references per body, handed out by CompositeReference's factory.
std::unique_ptr<ReferenceFactorization> read_reference(const SavedFileReader &r, const ContactSession &session, std::size_t bodies)
{
  if (bodies == 1) return read_dense(r, "reference");
  std::vector<std::unique_ptr<DenseReference>> parts;
  for (std::size_t b = 0; b < bodies; ++b) parts.push_back(read_dense(r, "body" + std::to_string(b)));
  const BodyReferenceFactory hand_out = [&](const BemOperator &, std::vector<char> pattern, std::vector<char>, int b) -> std::unique_ptr<ReferenceFactorization> {
    if (b >= static_cast<int>(parts.size()) || !parts[b] || parts[b]->pattern() != pattern) r.fail("its reference of body " + std::to_string(b) + " does not fit the body");
    return std::move(parts[b]);
  };
  try {
    return std::make_unique<CompositeReference>(session.problem().op(), node_bodies(session.problem().disc()), session.job().base.unknown_pattern(), std::vector<char>{}, hand_out);
  } catch (const std::invalid_argument &e) {
    r.fail(std::string("its references do not fit the bodies: ") + e.what());
  }
}

} // namespace

void save_precomputation(const ContactSession &session, const std::string &path, const std::vector<std::string> &inputs)
{
  const std::shared_ptr<ContactPrecomputation> &pre = session.precomputation();
  if (!pre || !pre->columns) throw std::invalid_argument("cannot save '" + path + "': the contact is not set up");
  if (std::any_of(pre->on_h2.begin(), pre->on_h2.end(), [](char h) { return h != 0; }))
    throw std::invalid_argument("cannot save '" + path + "': an H2 reference factorization cannot be saved yet (only dense ones: -bem_mat_type dense)");
  SavedFileWriter w(path, inputs, kKind, kPrecomputationFormat);
  write_fingerprint(w, pre->fingerprint);
  w.chars("on_h2", pre->on_h2.data(), pre->on_h2.size());
  if (const auto *c = dynamic_cast<const CompositeReference *>(pre->reference.get())) {
    for (int b = 0; b < c->num_bodies(); ++b) write_dense(w, "body" + std::to_string(b), dynamic_cast<const DenseReference &>(c->body_reference(b)));
  } else {
    write_dense(w, "reference", dynamic_cast<const DenseReference &>(*pre->reference));
  }
  write_columns(w, *pre->columns);
  w.commit();
}

void check_contact_reference_saveable(const std::string &mat_type, const std::string &option, const std::string &remedy)
{
  if (mat_type != "dense")
    throw std::invalid_argument(option + ": only dense reference factorizations are saved and loaded yet; this contact takes the " + mat_type + " one" + remedy);
}

std::shared_ptr<ContactPrecomputation> load_precomputation(const ContactSession &session, const std::string &path)
{
  const SavedFileReader r(path, kKind, kPrecomputationFormat);
  auto pre = std::make_shared<ContactPrecomputation>();
  pre->fingerprint = read_fingerprint(r);
  const std::string why = session.fingerprint().difference(pre->fingerprint);
  if (!why.empty()) r.fail(why);
  pre->on_h2 = r.chars("on_h2");
  if (pre->on_h2.size() != session.on_h2().size() || std::any_of(pre->on_h2.begin(), pre->on_h2.end(), [](char h) { return h != 0; }))
    r.fail("its references are not the dense ones of this problem's " + std::to_string(session.on_h2().size()) + " bodies");
  pre->reference = read_reference(r, session, pre->on_h2.size());
  if (pre->reference->pattern() != session.job().base.unknown_pattern()) r.fail("its reference pattern is not this problem's");
  pre->columns = read_columns(r, *pre->reference);
  return pre;
}

void save_scene_precomputation(const SceneSession &session, const std::string &path, const std::vector<std::string> &inputs)
{
  if (!session.is_set_up()) throw std::invalid_argument("cannot save '" + path + "': the scene is not set up");
  const DenseScene &scene = session.engine();
  SavedFileWriter w(path, inputs, kSceneKind, kPrecomputationFormat);
  write_fingerprint(w, session.fingerprint());
  write_dense(w, "reference", scene.reference());
  w.doubles("scene/W", scene.columns().data(), scene.columns().size());
  w.doubles("scene/Wp", scene.pressure_columns().data(), scene.pressure_columns().size());
  w.doubles("scene/rates", scene.rates().data(), scene.rates().size());
  w.commit();
}

DenseScene::Saved load_scene_precomputation(const SceneSession &session, const std::string &path)
{
  const SavedFileReader r(path, kSceneKind, kPrecomputationFormat);
  const std::string why = session.fingerprint().difference(read_fingerprint(r));
  if (!why.empty()) r.fail(why);
  DenseScene::Saved s;
  s.reference = read_dense(r, "reference");
  if (s.reference->pattern() != session.reference().pattern()) r.fail("its reference pattern is not this problem's");
  s.W.resize(r.size("scene/W"));
  r.doubles("scene/W", s.W.data(), s.W.size());
  s.Wp = r.doubles("scene/Wp");
  const std::vector<double> rates = r.doubles("scene/rates");
  if (rates.size() != s.rates.size()) r.fail("its scene's rates are damaged");
  std::copy(rates.begin(), rates.end(), s.rates.begin());
  return s;
}

void ContactSession::save(const std::string &path, const std::vector<std::string> &inputs) const { save_precomputation(*this, path, inputs); }

void ContactSession::load(const std::string &path) { adopt(load_precomputation(*this, path)); }

} // namespace hssbem
