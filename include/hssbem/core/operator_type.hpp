/// \file operator_type.hpp
/// The representations of the BEM operator that the library builds: assembled dense, or
/// compressed in the HSS or the H² format. The driver picks one with -bem_mat_type, programs
/// with the mat_type string of HssbemCreateSystem() (petsc/system.h: HSSBEM_MAT_DENSE, _HSS,
/// _H2); both are spelled as operator_type_name() spells them and read by parse_operator_type().
#pragma once

#include <optional>
#include <string_view>

namespace hssbem {

enum class OperatorType { Dense, Hss, H2 };

/// "dense", "hss" or "h2".
const char *operator_type_name(OperatorType type);

/// The type that operator_type_name() calls `name`, or nothing for any other string.
std::optional<OperatorType> parse_operator_type(std::string_view name);

/// A compressed operator (HSS or H²) has no entries to factor; only its products and diagonal.
inline bool is_compressed(OperatorType type) { return type != OperatorType::Dense; }

} // namespace hssbem
