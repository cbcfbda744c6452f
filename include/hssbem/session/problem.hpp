/// \file problem.hpp
/// What a session solves: a prepared problem (problem/setup.hpp: the mesh, its dof nodes, the
/// material and the boundary conditions, from a problem file or made in memory) with its BEM
/// operator, built once and shared by the session and whatever face made it.
#pragma once

#include "hssbem/bem/bem_operator.hpp"
#include "hssbem/bem/quadrature.hpp"
#include "hssbem/problem/setup.hpp"

#include <memory>
#include <string>

namespace hssbem {

/// The job a problem asks for: a static solve, a scene of frames, or contact (once or per frame).
enum class JobKind { Static, Scene, Contact };

/// "static", "scene", "contact".
const char *job_name(JobKind job);

/// The job of a problem file: contact when it has "contact", a scene when it has "frames", else
/// a static solve.
JobKind job_of(const ProblemSpec &spec);

class SessionProblem {
public:
  /// Owns `setup` and the operator of its dof nodes and material with the quadrature `quad`
  /// (every rank that works on the problem builds it).
  SessionProblem(std::shared_ptr<const ProblemSetup> setup, const QuadratureOptions &quad);
  /// A view of a set-up and its operator that the caller keeps alive (tests, benchmarks).
  SessionProblem(const ProblemSetup &setup, const BemOperator &op) : m_setup(&setup), m_op(&op) {}
  SessionProblem(const SessionProblem &) = delete; // the operator points into the set-up
  SessionProblem &operator=(const SessionProblem &) = delete;

  const ProblemSetup &setup() const { return *m_setup; }
  const SurfaceMesh &mesh() const { return *m_setup->mesh; }
  const Discretization &disc() const { return *m_setup->disc; }
  const Material &material() const { return m_setup->material; }
  const BemOperator &op() const { return *m_op; }
  long long unknowns() const { return 3LL * m_setup->disc->num_nodes(); }
  JobKind job() const { return job_of(m_setup->spec); }
  /// "<problem file>: " for messages, or nothing for a problem made in memory.
  std::string where() const { return m_setup->spec.file.empty() ? "" : m_setup->spec.file + ": "; }

private:
  std::shared_ptr<const ProblemSetup> m_owned;
  std::unique_ptr<BemOperator> m_owned_op;
  const ProblemSetup *m_setup;
  const BemOperator *m_op;
};

} // namespace hssbem
