// A problem set up by hand on any mesh, for the contact tests on meshes the problem file does not
// describe (a turned cube, several cubes side by side): per dof node which displacement
// components are prescribed and their values, and the static answer of that pattern.
#pragma once

#include "hssbem/bem/bem_operator.hpp"
#include "hssbem/post/post.hpp"
#include "hssbem/reference/reference.hpp"

#include <functional>
#include <memory>
#include <vector>

namespace hssbem::test {

struct HandProblem {
  SurfaceMesh mesh;
  std::unique_ptr<Discretization> disc;
  std::unique_ptr<BemOperator> op;
  SystemSelection sel; ///< traction-free unless hold() says otherwise

  HandProblem(SurfaceMesh m, const Material &material) : mesh(std::move(m))
  {
    disc = std::make_unique<Discretization>(mesh, 40.0);
    op = std::make_unique<BemOperator>(*disc, material);
    sel = SystemSelection{std::vector<std::array<bool, 3>>(disc->num_nodes(), {false, false, false}), std::vector<Vec3>(disc->num_nodes(), Vec3{0, 0, 0}), {}};
  }
  /// Prescribes component c of every dof node of the vertices `where` selects (by index) to
  /// value(the vertex's position).
  void hold(const std::function<bool(int)> &where, int c, const std::function<double(const Vec3 &)> &value)
  {
    for (int i = 0; i < disc->num_nodes(); ++i)
      if (where(disc->node(i).vertex)) sel.displacement_known[i][c] = true, sel.known[i][c] = value(mesh.vertices[disc->node(i).vertex]);
  }
  /// The same for the vertices whose position `where` selects, to a constant value.
  void hold_at(const std::function<bool(const Vec3 &)> &where, int c, double value)
  {
    hold([&](int v) { return where(mesh.vertices[v]); }, c, [value](const Vec3 &) { return value; });
  }
  /// Per unknown: 1 where the displacement is prescribed.
  std::vector<char> pattern() const
  {
    std::vector<char> p(3 * sel.known.size());
    for (std::size_t i = 0; i < sel.known.size(); ++i)
      for (int c = 0; c < 3; ++c) p[3 * i + c] = sel.displacement_known[i][c];
    return p;
  }
  /// The static answer of the prescribed pattern and values (a dense reference of that pattern).
  NodalSolution statics() const
  {
    const DenseReference ref(*op, pattern());
    std::vector<double> x;
    ref.free_response(sel, x);
    return split_unknowns(sel, x);
  }
};

} // namespace hssbem::test
