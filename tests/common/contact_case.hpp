// A contact problem set up in code on the dense reference of its base rules, for the contact
// tests (tests/verification/test_contact*.cpp).
#pragma once

#include "solve_helpers.hpp"

#include "hssbem/contact/contact_engine.hpp"
#include "hssbem/reference/reference.hpp"

#include <memory>

namespace hssbem::test {

/// The problem `spec` with `obstacles`: its set-up, operator, base conditions, reference and
/// engine; solve() fills `sol` and `rep`.
struct ContactCase {
  ProblemSetup s;
  std::unique_ptr<BemOperator> op;
  NodeConditions base;
  std::unique_ptr<DenseReference> ref;
  std::unique_ptr<ContactEngine> engine;
  ContactSolution sol;
  ContactFrameReport rep;

  ContactCase(ProblemSpec spec, std::vector<Obstacle> obstacles, const ContactSettings &settings = {}, const ContactOptions &opt = {})
  {
    spec.contact.present = true;
    s = setup_problem(std::move(spec), ProblemOverrides{});
    op = std::make_unique<BemOperator>(*s.disc, s.material);
    base = apply_rules(s.spec.rules, *s.disc, s.spec.file);
    // A body contact alone holds is pinned as the contact session pins it (floating_pins()).
    ContactSettings pinned = settings;
    pinned.pins = floating_pins(*s.disc, base.displacement_prescribed, obstacles, pinned, opt);
    for (int j : pinned.pins) base.displacement_prescribed[j / 3][j % 3] = true, base.value[j / 3][j % 3] = 0;
    ref = std::make_unique<DenseReference>(*op, base.unknown_pattern());
    engine = std::make_unique<ContactEngine>(*s.disc, *ref, std::move(obstacles), pinned, opt);
  }
  /// The frame with the obstacles at `offsets` (one per obstacle).
  const ContactFrameReport &solve(const std::vector<Vec3> &offsets)
  {
    rep = engine->solve(selection_of(base), offsets, sol);
    return rep;
  }
};

} // namespace hssbem::test
