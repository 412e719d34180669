#include "hypershape/factory/solve_counters.hpp"

#include <array>

namespace hypershape::factory {

namespace {

constexpr std::size_t kCounters = 12;

/// The counters in one fixed order (C: SolveCounters or const SolveCounters).
template <class C>
auto fields(C& c) {
  return std::array{&c.loads_ok, &c.loads_failed, &c.newton_iterations, &c.solves, &c.failed_increments,
          &c.off_path_increments, &c.recovery_iterations, &c.linear.numeric_factorizations,
          &c.linear.symbolic_factorizations, &c.linear.krylov_iterations, &c.linear.tangent_assemblies,
          &c.linear.modified_solves};
}

}  // namespace

void SolveCounters::add(const solver::TargetResult& r) {
  newton_iterations += r.newton_iterations;
  solves += r.solves;
  failed_increments += r.failed_increments;
  off_path_increments += r.off_path_increments;
  recovery_iterations += r.recovery_iterations;
  linear += r.linear;
}

SolveCounters& SolveCounters::operator+=(const SolveCounters& o) {
  auto mine = fields(*this);
  const auto theirs = fields(o);
  for (std::size_t i = 0; i < mine.size(); ++i) *mine[i] += *theirs[i];
  return *this;
}

void SolveCounters::sum_over(MPI_Comm comm, bool contribute) {
  auto f = fields(*this);
  static_assert(std::tuple_size_v<decltype(f)> == kCounters);
  std::array<std::int64_t, kCounters> v{}, total{};
  for (std::size_t i = 0; i < f.size(); ++i) v[i] = contribute ? *f[i] : 0;
  MPI_Allreduce(v.data(), total.data(), int(v.size()), MPI_INT64_T, MPI_SUM, comm);
  for (std::size_t i = 0; i < f.size(); ++i) *f[i] = total[i];
}

nlohmann::json SolveCounters::solver_json() const {
  return {{"newton_iterations", newton_iterations},
          {"nonlinear_solves", solves},
          {"failed_increments", failed_increments},
          {"off_path_increments", off_path_increments},
          {"recovery_iterations", recovery_iterations},
          {"numeric_factorizations", linear.numeric_factorizations},
          {"symbolic_factorizations", linear.symbolic_factorizations},
          {"krylov_iterations", linear.krylov_iterations},
          {"tangent_assemblies", linear.tangent_assemblies},
          {"modified_newton_solves", linear.modified_solves}};
}

}  // namespace hypershape::factory
