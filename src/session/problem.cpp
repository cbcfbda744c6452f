// What a session solves (see problem.hpp).
#include "hssbem/session/problem.hpp"

namespace hssbem {

const char *job_name(JobKind job)
{
  switch (job) {
  case JobKind::Static: return "static";
  case JobKind::Scene: return "scene";
  case JobKind::Contact: return "contact";
  }
  return "";
}

JobKind job_of(const ProblemSpec &spec)
{
  if (spec.contact.present) return JobKind::Contact;
  return spec.frames.empty() ? JobKind::Static : JobKind::Scene;
}

SessionProblem::SessionProblem(std::shared_ptr<const ProblemSetup> setup, const QuadratureOptions &quad)
    : m_owned(std::move(setup)), m_owned_op(std::make_unique<BemOperator>(*m_owned->disc, m_owned->material, quad)), m_setup(m_owned.get()), m_op(m_owned_op.get())
{
}

} // namespace hssbem
