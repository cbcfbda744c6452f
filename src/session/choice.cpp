// The operator and the reference of each job (see choice.hpp).
#include "hssbem/session/choice.hpp"

#include "hssbem/contact/bodies.hpp"

#include <algorithm>
#include <stdexcept>

namespace hssbem {

OperatorType choose_operator(long long unknowns, const MachineLimits &limits)
{
  if (unknowns < k_auto_dense_max_unknowns && size_refusal(OperatorType::Dense, unknowns, SizeOptions{}, limits).empty()) return OperatorType::Dense;
  return OperatorType::H2;
}

OperatorChoice static_operator(std::optional<OperatorType> asked, long long unknowns, const MachineLimits &limits)
{
  if (asked) return {*asked, ""};
  OperatorChoice c{choose_operator(unknowns, limits), ""};
  if (c.type == OperatorType::Dense) c.why = " (auto: below " + std::to_string(k_auto_dense_max_unknowns) + " unknowns)";
  else if (unknowns < k_auto_dense_max_unknowns) c.why = " (auto: the dense operator does not fit this machine)";
  else c.why = " (auto: from " + std::to_string(k_auto_dense_max_unknowns) + " unknowns on)";
  return c;
}

std::vector<char> contact_references_on_h2(const Discretization &disc, std::optional<OperatorType> asked, const MachineLimits &limits)
{
  if (asked && *asked == OperatorType::Hss)
    throw std::runtime_error("-bem_mat_type hss: contact runs on the dense or the H2 reference factorization; use -bem_mat_type dense, h2 or auto");
  const std::vector<int> node_body = node_bodies(disc);
  std::vector<double> unknowns(node_body.empty() ? 1 : *std::max_element(node_body.begin(), node_body.end()) + 1, 0.0);
  for (int i = 0; i < disc.num_nodes(); ++i) unknowns[node_body.empty() ? 0 : node_body[i]] += 3;
  const double room = 0.9 * static_cast<double>(limits.node_memory_bytes);
  std::vector<char> h2(unknowns.size(), asked && *asked == OperatorType::H2);
  double need = 0, total = 0;
  for (std::size_t b = 0; b < unknowns.size(); ++b) {
    const double nb = 8.0 * unknowns[b] * unknowns[b] * 3.0; // the LU, K₀′ (at most), W's columns (at most N_b)
    total += nb;
    if (asked) continue;
    h2[b] = need + nb > room;
    if (!h2[b]) need += nb;
  }
  if (asked && *asked == OperatorType::Dense && total > room)
    throw std::runtime_error("contact needs about " + std::to_string(static_cast<long long>(total / 1e9 + 0.5)) + " GB for " + std::to_string(3LL * disc.num_nodes()) +
                             " unknowns (dense reference factorization, the operator's columns, W's columns), more than this node's " +
                             std::to_string(static_cast<long long>(limits.node_memory_bytes / 1e9)) + " GB; use -bem_mat_type h2");
  return h2;
}

std::string reference_mat_type(const std::vector<char> &on_h2)
{
  const bool any = std::any_of(on_h2.begin(), on_h2.end(), [](char c) { return c != 0; }), all = std::all_of(on_h2.begin(), on_h2.end(), [](char c) { return c != 0; });
  return all ? "h2" : any ? "dense,h2" : "dense";
}

void check_scene_operator(std::optional<OperatorType> asked)
{
  if (asked && *asked != OperatorType::Dense)
    throw std::runtime_error(std::string("-bem_mat_type ") + operator_type_name(*asked) + ": scenes (problem files with \"frames\") run on the dense scene engine; use -bem_mat_type dense or auto");
}

void check_scene_size(long long unknowns, long long candidates, bool pressure, SceneStrategy strategy, const MachineLimits &limits)
{
  const double N = static_cast<double>(unknowns), k = static_cast<double>(candidates);
  const double need = 8.0 * N * N * (pressure ? 6.7 : 6.0) * (strategy == SceneStrategy::Refactor || strategy == SceneStrategy::Auto ? 1.0 : 5.0 / 6.0) -
                      8.0 * N * (N - k) + // W's columns that are no candidates
                      4.0 * N * k;        // W's single-precision copy
  if (need > 0.9 * static_cast<double>(limits.node_memory_bytes))
    throw std::runtime_error("the scene needs about " + std::to_string(static_cast<long long>(need / 1e9 + 0.5)) + " GB for " + std::to_string(unknowns) +
                             " unknowns (dense reference factorization, W = A0^-1 K0', H and G), more than this node's " +
                             std::to_string(static_cast<long long>(limits.node_memory_bytes / 1e9)) + " GB");
}

} // namespace hssbem
