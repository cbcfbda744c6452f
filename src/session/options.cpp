// The jobs' options, typed (see options.hpp): each option's field, its checks, and back.
#include "hssbem/session/options.hpp"

#include <climits>
#include <functional>
#include <stdexcept>
#include <string>

namespace hssbem {

namespace {

/// Where one option lives in SessionOptions: how to set it from a value, how to read it back.
struct Binding {
  const char *name;
  std::function<void(SessionOptions &, const OptionValue &)> set;
  std::function<OptionValue(const SessionOptions &)> get;
};

void assign(double &field, const OptionValue &v) { field = v.number; }
void assign(int &field, const OptionValue &v) { field = static_cast<int>(v.number); }
void assign(bool &field, const OptionValue &v) { field = v.number != 0; }
double number(double v) { return v; }
double number(int v) { return v; }
double number(bool v) { return v ? 1 : 0; }

/// A field whose value is the option's (doubles, ints, bools).
#define HSSBEM_BIND(key, path) \
  Binding { key, [](SessionOptions &o, const OptionValue &v) { assign(o.path, v); }, [](const SessionOptions &o) { return OptionValue::of(*find_option(key), number(o.path)); } }

/// "Never" is -1 on the command line and INT_MAX in the engines (SceneOptions::single_from).
#define HSSBEM_BIND_NEVER(key, path) \
  Binding { \
    key, [](SessionOptions &o, const OptionValue &v) { o.path = v.number < 0 ? INT_MAX : static_cast<int>(v.number); }, \
        [](const SessionOptions &o) { return OptionValue::of(*find_option(key), o.path == INT_MAX ? -1.0 : static_cast<double>(o.path)); } \
  }

const std::vector<Binding> &bindings()
{
  static const std::vector<Binding> all = {
      Binding{"bem_mat_type",
              [](SessionOptions &o, const OptionValue &v) { o.operator_type = parse_operator_type(v.text); },
              [](const SessionOptions &o) { return OptionValue::of(*find_option("bem_mat_type"), std::string(o.operator_type ? operator_type_name(*o.operator_type) : "auto")); }},
      HSSBEM_BIND("mat_bem_quad_order", quad.duffy_order),
      HSSBEM_BIND("mat_bem_near_ratio", quad.near_ratio),
      HSSBEM_BIND("mat_bem_far_ratio", quad.far_ratio),
      HSSBEM_BIND("mat_bem_max_depth", quad.max_depth),
      HSSBEM_BIND("mat_h2_rel_tol", h2.rel_tol),
      HSSBEM_BIND("mat_h2_leaf_size", h2.leaf_size),
      HSSBEM_BIND("mat_h2_max_rank", h2.max_rank),
      HSSBEM_BIND("mat_h2_proxy_ratio", h2.proxy_ratio),
      HSSBEM_BIND("mat_h2_proxy_points", h2.proxy_points),
      HSSBEM_BIND("mat_h2_eta", h2.eta),
      HSSBEM_BIND("mat_h2_single_precision", h2.single_precision),
      HSSBEM_BIND("mat_hss_rel_tol", hss.rel_tol),
      HSSBEM_BIND("mat_hss_leaf_size", hss.leaf_size),
      HSSBEM_BIND("mat_hss_max_rank", hss.max_rank),
      HSSBEM_BIND("mat_hss_proxy_ratio", hss.proxy_ratio),
      HSSBEM_BIND("mat_hss_proxy_points", hss.proxy_points),
      Binding{"scene_strategy",
              [](SessionOptions &o, const OptionValue &v) { o.scene.strategy = *parse_scene_strategy(v.text); },
              [](const SessionOptions &o) { return OptionValue::of(*find_option("scene_strategy"), std::string(scene_strategy_name(o.scene.strategy))); }},
      HSSBEM_BIND("scene_refresh", scene.refresh_every),
      HSSBEM_BIND_NEVER("scene_single_from", scene.single_from),
      HSSBEM_BIND_NEVER("scene_single_fields_from", scene.single_fields_from),
      HSSBEM_BIND("scene_krylov_rtol", scene.krylov_rtol),
      HSSBEM_BIND("contact_tol", contact.tol),
      HSSBEM_BIND("contact_max_it", contact.max_it),
      HSSBEM_BIND("contact_reach", contact.reach),
      HSSBEM_BIND("contact_depth", contact.depth),
      HSSBEM_BIND("contact_pair_again", contact.pair_again),
      HSSBEM_BIND("contact_h2_rtol", contact_h2_rtol),
      HSSBEM_BIND("contact_h2_factor_tol", contact_h2_factor_tol),
      HSSBEM_BIND("bem_interior_band", interior.plan.band),
      HSSBEM_BIND("bem_interior_near_ratio", interior.quad.near_ratio),
      HSSBEM_BIND("bem_interior_max_depth", interior.quad.max_depth),
      HSSBEM_BIND("bem_interior_equivalent_points", interior.fast.equivalent_points),
      HSSBEM_BIND("bem_interior_inner_points", interior.fast.inner_points),
      HSSBEM_BIND("bem_interior_source_leaf", interior.fast.source_leaf),
      HSSBEM_BIND("bem_interior_target_leaf", interior.fast.target_leaf),
      HSSBEM_BIND("bem_interior_direct", interior.fast.direct),
  };
  return all;
}

#undef HSSBEM_BIND
#undef HSSBEM_BIND_NEVER

/// The rules between options (each option's own range is the table's).
void check_rules(const SessionOptions &o)
{
  const QuadratureOptions &q = o.quad;
  if (q.far_ratio != 0 && q.far_ratio < q.near_ratio)
    throw std::invalid_argument("-mat_bem_far_ratio must be 0 (off) or at least -mat_bem_near_ratio (" + std::to_string(q.near_ratio) + ")");
  if (q.far_ratio != 0 && !(o.operator_type && !is_compressed(*o.operator_type)))
    throw std::invalid_argument(std::string("-mat_bem_far_ratio must be 0 with -bem_mat_type ") + (o.operator_type ? operator_type_name(*o.operator_type) : "auto") +
                                ": the 3-point far rule breaks the smooth far field the compression relies on (use -bem_mat_type dense)");
}

} // namespace

SessionOptions session_options(const OptionValues &given)
{
  SessionOptions o;
  for (const Binding &b : bindings()) {
    const auto it = given.find(b.name);
    if (it == given.end()) continue;
    check_option(*find_option(b.name), it->second);
    b.set(o, it->second);
  }
  check_rules(o);
  return o;
}

OptionValues option_values(const SessionOptions &o, unsigned jobs)
{
  OptionValues out;
  for (const Binding &b : bindings())
    if (find_option(b.name)->jobs & jobs) out[b.name] = b.get(o);
  return out;
}

H2ReferenceOptions h2_reference_options(const SessionOptions &o)
{
  H2ReferenceOptions ho;
  ho.compression = o.h2;
  ho.rtol = o.contact_h2_rtol;
  ho.factor.rel_tol = o.contact_h2_factor_tol;
  return ho;
}

} // namespace hssbem
