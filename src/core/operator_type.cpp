#include "hssbem/core/operator_type.hpp"

namespace hssbem {

namespace {

struct Named {
  OperatorType type;
  const char *name;
};

constexpr Named k_names[] = {{OperatorType::Dense, "dense"}, {OperatorType::Hss, "hss"}, {OperatorType::H2, "h2"}};

} // namespace

const char *operator_type_name(OperatorType type)
{
  for (const Named &n : k_names)
    if (n.type == type) return n.name;
  return "unknown";
}

std::optional<OperatorType> parse_operator_type(std::string_view name)
{
  for (const Named &n : k_names)
    if (name == n.name) return n.type;
  return std::nullopt;
}

} // namespace hssbem
