/// \file options.hpp
/// The options of the jobs, typed: what the session layer hands down to the engines. A face (the
/// command line, the Python module, a program) gathers the values it was given as OptionValues
/// (core/option_table.hpp); session_options() puts them over the table's defaults (the engines'
/// option structs start from those) and checks them, once, against the table's ranges and the
/// rules between options. option_values() gives back what a job uses, for the result file.
///
/// PETSc's own objects read their options themselves: the main KSP (-ksp_*, -pc_type) and the
/// PCs hss and h2 (-pc_hss_*, -pc_h2_*) in their SetFromOptions (petsc/); the static session
/// reports what they used (StaticSession::options_used()).
#pragma once

#include "hssbem/bem/quadrature.hpp"
#include "hssbem/contact/contact_engine.hpp"
#include "hssbem/core/operator_type.hpp"
#include "hssbem/core/option_table.hpp"
#include "hssbem/h2/h2_compression.hpp"
#include "hssbem/hss/hss_compression.hpp"
#include "hssbem/interior/interior_evaluation.hpp"
#include "hssbem/post/interior_stress.hpp"
#include "hssbem/post/near_surface.hpp"
#include "hssbem/reference/h2_reference.hpp"
#include "hssbem/scene/dense_scene.hpp"

#include <optional>

namespace hssbem {

/// Displacement and stress inside the body (interior points and grids), -bem_interior_*.
struct InteriorRunOptions {
  InteriorQuadrature quad;        ///< -bem_interior_near_ratio, -bem_interior_max_depth
  InteriorPlanOptions plan;       ///< -bem_interior_band
  InteriorEvaluationOptions fast; ///< -bem_interior_equivalent_points, _inner_points, _source_leaf, _target_leaf, _direct
};

/// Everything a session takes from the options, for every job.
struct SessionOptions {
  std::optional<OperatorType> operator_type; ///< -bem_mat_type: the operator (static) or the reference (scene, contact); none: auto
  QuadratureOptions quad;                    ///< -mat_bem_*
  H2Options h2;                              ///< -mat_h2_*: the H² operator, and the H² references of contact
  HssOptions hss;                            ///< -mat_hss_*
  SceneOptions scene;                        ///< -scene_strategy, _refresh, _single_from, _single_fields_from, _krylov_rtol
  ContactOptions contact;                    ///< -contact_tol, _max_it, _reach (the monitor is the face's)
  double contact_h2_rtol = option_default::contact_h2_rtol;             ///< -contact_h2_rtol: an H² reference's accurate solves
  double contact_h2_factor_tol = option_default::contact_h2_factor_tol; ///< -contact_h2_factor_tol: an H² reference's factorization
  InteriorRunOptions interior;               ///< -bem_interior_*
};

/// The options `given` (by name, without the dash) over the defaults, each checked against the
/// table's range, then the rules between them (-mat_bem_far_ratio: 0, or at least
/// -mat_bem_near_ratio with the dense operator). A name the session does not take is ignored
/// (the face's own options: -problem, -scene_monitor, ...). Throws std::invalid_argument naming
/// the option.
SessionOptions session_options(const OptionValues &given);

/// The values of `o` for the options that apply to one of `jobs` (OptionJob bits), by name.
OptionValues option_values(const SessionOptions &o, unsigned jobs);

/// The H² reference options of o: the compression -mat_h2_*, the factorization at
/// -contact_h2_factor_tol, the accurate solves at -contact_h2_rtol.
H2ReferenceOptions h2_reference_options(const SessionOptions &o);

} // namespace hssbem
