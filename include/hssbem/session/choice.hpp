/// \file choice.hpp
/// Which operator a static solve takes, and which reference factorization a scene or a contact
/// stands on: the one asked for (-bem_mat_type), or auto's choice by the problem's size and the
/// machine's memory (core/size_limits.hpp). One place for every job and every face.
#pragma once

#include "hssbem/bem/discretization.hpp"
#include "hssbem/core/operator_type.hpp"
#include "hssbem/core/size_limits.hpp"
#include "hssbem/scene/dense_scene.hpp"

#include <optional>
#include <string>
#include <vector>

namespace hssbem {

/// -bem_mat_type auto picks the dense operator below this many unknowns and the H² operator
/// (with its default solver, GMRES + PC h2) from it on. Measured with benchmarks/bench_h2_factor
/// at the driver's H² defaults (tol 1e-5, single-precision blocks, leaf 64, eta 0; PC h2 at 3e-3,
/// rtol 1e-8) beside dense assembly + LU in the same run, 1 process, 2 threads, sphere meshes:
/// dense faster at 3 036 and 4 983 unknowns (2.3x, 1.2x), H² faster at 6 990 (1.4x) and 9 030
/// (1.9x): benchmarks/results/2026-11-23-h2-defaults.md (docs/performance.md).
inline constexpr long long k_auto_dense_max_unknowns = 6000;

/// The operator -bem_mat_type auto takes for `unknowns` unknowns on this machine: dense below
/// k_auto_dense_max_unknowns when the dense operator fits (size_refusal()), else H².
OperatorType choose_operator(long long unknowns, const MachineLimits &limits);

/// A static solve's operator and, when auto chose it, why (" (auto: below 6000 unknowns)").
struct OperatorChoice {
  OperatorType type = OperatorType::Dense;
  std::string why;
};

/// The operator asked for, or auto's choice.
OperatorChoice static_operator(std::optional<OperatorType> asked, long long unknowns, const MachineLimits &limits);

/// Contact: per body (one entry when the mesh is one body), whether its reference is the H² one:
/// all when asked (-bem_mat_type h2), none when dense is asked (std::runtime_error when they do
/// not fit the node's memory together); with auto, the bodies in order take the dense reference
/// while the dense ones fit the node's memory together, the others the H² one. HSS is refused.
std::vector<char> contact_references_on_h2(const Discretization &disc, std::optional<OperatorType> asked, const MachineLimits &limits);

/// "dense", "h2", or "dense,h2" (bodies on both), for the result file's mat_type.
std::string reference_mat_type(const std::vector<char> &on_h2);

/// Scenes run on the dense scene engine: std::runtime_error for -bem_mat_type hss or h2.
void check_scene_operator(std::optional<OperatorType> asked);

/// The dense scene's memory (W's candidate columns and their single-precision copy, the
/// reference LU, H and G and the pressure columns) against the node's: std::runtime_error when
/// it does not fit.
void check_scene_size(long long unknowns, long long candidates, bool pressure, SceneStrategy strategy, const MachineLimits &limits);

} // namespace hssbem
