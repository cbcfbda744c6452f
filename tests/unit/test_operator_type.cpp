// The operator-type names: one spelling for -bem_mat_type, HSSBEM_MAT_* and the result file.
#include "hssbem/core/operator_type.hpp"
#include "hssbem/petsc/system.h"

#include <gtest/gtest.h>

#include <optional>
#include <string>

using namespace hssbem;

TEST(OperatorType, NamesRoundTrip)
{
  for (OperatorType t : {OperatorType::Dense, OperatorType::Hss, OperatorType::H2}) {
    const std::optional<OperatorType> back = parse_operator_type(operator_type_name(t));
    ASSERT_TRUE(back.has_value()) << operator_type_name(t);
    EXPECT_EQ(*back, t);
  }
  EXPECT_FALSE(parse_operator_type("HSS").has_value());
  EXPECT_FALSE(parse_operator_type("").has_value());
  EXPECT_FALSE(is_compressed(OperatorType::Dense));
  EXPECT_TRUE(is_compressed(OperatorType::Hss));
  EXPECT_TRUE(is_compressed(OperatorType::H2));
}

TEST(OperatorType, PetscFaceConstantsAreTheNames)
{
  EXPECT_EQ(std::string(HSSBEM_MAT_DENSE), operator_type_name(OperatorType::Dense));
  EXPECT_EQ(std::string(HSSBEM_MAT_HSS), operator_type_name(OperatorType::Hss));
  EXPECT_EQ(std::string(HSSBEM_MAT_H2), operator_type_name(OperatorType::H2));
}
