#include "hypershape/factory/p1_start.hpp"

#include <algorithm>
#include <array>
#include <stdexcept>
#include <vector>

#include "hypershape/core/error.hpp"

namespace hypershape::factory {

namespace {

/// The edges of a P2 cell in canonical (VTK) order: (midpoint node, end, end).
constexpr std::array<std::array<int, 3>, 3> triangle_edges{{{3, 0, 1}, {4, 1, 2}, {5, 2, 0}}};
constexpr std::array<std::array<int, 3>, 6> tetrahedron_edges{
    {{4, 0, 1}, {5, 1, 2}, {6, 2, 0}, {7, 0, 3}, {8, 1, 3}, {9, 2, 3}}};

/// The P2 nodal values (canonical order, n x d) of the P1 ones (the vertices, first): on the
/// group root; elsewhere empty.
std::vector<double> p2_values(const physics::Space& s2, const std::vector<double>& p1) {
  const int d = s2.dim();
  const auto& cells = s2.canonical_cells();
  std::vector<double> v(s2.canonical_coords().size(), 0.0);
  if (p1.size() > v.size()) throw std::logic_error("prolong_p1_to_p2: the P1 field has more nodes than the P2 space");
  std::copy(p1.begin(), p1.end(), v.begin());
  const std::size_t per_cell = d == 2 ? 6 : 10;
  auto mean = [&](const std::int64_t* c, const auto& edges) {
    for (const auto& e : edges)
      for (int k = 0; k < d; ++k)
        v[std::size_t(c[e[0]] * d + k)] = 0.5 * (v[std::size_t(c[e[1]] * d + k)] + v[std::size_t(c[e[2]] * d + k)]);
  };
  for (std::size_t c = 0; c + per_cell <= cells.size(); c += per_cell)
    d == 2 ? mean(&cells[c], triangle_edges) : mean(&cells[c], tetrahedron_edges);
  return v;
}

}  // namespace

core::VecH prolong_p1_to_p2(const physics::Problem& p1, Vec u1, const physics::Problem& p2) {
  const physics::Space& s2 = p2.space();
  if (p1.space().degree() != 1 || s2.degree() != 2) throw std::logic_error("prolong_p1_to_p2: P1 to P2 only");
  const physics::NodalField f1 = p1.gather(u1);
  return p2.scatter(core::rank(p2.comm()) == 0 ? p2_values(s2, f1.values) : std::vector<double>{});
}

bool P1Start::applies(const solver::TargetResult& failed) const {
  // 2D only: measured there (docs/SOLVER.md); the 3D presets lose too few load cases (1 of 200
  // on an unseen seed) to measure it on.
  return cfg_.solver.p1_start && cfg_.degree == 2 && cfg_.shapes.dim == 2 && !failed.converged && failed.solves > 0 &&
         !solver::verified_fold(failed.reason);
}

std::optional<solver::TargetResult> P1Start::solve(const LoadCase& lc, solver::NonlinearSolver& p2,
                                                   const solver::TargetResult& failed, std::string& note) {
  if (!nl_) {
    sp_ = make_shape_problem(group_, cfg_, shape_, lc, physics::SpaceOptions{1, 0, 0});
    nl_ = std::make_unique<solver::NonlinearSolver>(*sp_.problem, cfg_.solver);
  }
  sp_.set_load_case(cfg_, shape_, lc);
  nl_->reset();
  const solver::TargetResult p1 = nl_->solve_for_target(lc.target);
  if (!p1.converged) {
    note = "; P1 on the same mesh: " + p1.reason.substr(0, 200);
    return std::nullopt;
  }
  const core::VecH start = prolong_p1_to_p2(*sp_.problem, nl_->solution(), p2.problem());
  solver::TargetResult t = p2.solve_for_target_from(start, p1.alpha, lc.target);
  t.add_discarded_solve(failed);
  t.newton_iterations += p1.newton_iterations;  // P1's, discarded work too (each a quarter of a P2 one's cost)
  t.recovery_iterations += p1.newton_iterations;
  t.linear += p1.linear;  // the factorisations of all three solves
  t.seconds_total += p1.seconds_total;
  t.reason = t.converged ? "target reached from the P1 solution on the same mesh (" + t.reason.substr(0, 200) +
                               "; first try: " + failed.reason.substr(0, 300) + ")"
                         : failed.reason.substr(0, 400) + "; from the P1 solution on the same mesh: " +
                               t.reason.substr(0, 300);
  return t;
}

}  // namespace hypershape::factory
