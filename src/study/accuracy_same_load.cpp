// The same-load (training-pair) error of the accuracy study.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <tuple>

#include "accuracy_detail.hpp"
#include "hypershape/core/timer.hpp"
#include "hypershape/study/stats.hpp"

namespace hypershape::study::accuracy {

/// The error of a sample as a training pair. The metrics above compare u at the same target
/// max|u|, where a too-stiff discretisation is compensated by a larger alpha; but a dataset
/// pairs u with the traction alpha g phi it was solved for, so what a model learns is off by
/// |u_h(alpha_h) - u(alpha_h)|. This pass re-solves the reference at its target (the state the
/// metrics above compare with), then continues it by load control through every setting's
/// alpha in ascending order, and stores "same_load_rel_l2" / "same_load_rel_h1" per load case
/// (and their means in the summary). A continuation that fails leaves them null, with a reason.
void same_load_pass(json& sc, const factory::ShapeSample& ref_shape, const config::DatasetConfig& cfg,
                    const std::vector<factory::LoadCase>& cases, const Setting& ref_set, const Reference& ref,
                    std::vector<SameLoad>& answers, const std::string& prefix, int d) {
  const double t0 = core::now_seconds();
  std::sort(answers.begin(), answers.end(), [](const SameLoad& x, const SameLoad& y) {
    return std::tie(x.load, x.alpha) < std::tie(y.load, y.alpha);
  });
  int n_ok = 0, n_failed = 0;
  auto after = [&](std::size_t l, solver::NonlinearSolver& nl, const physics::Problem& problem) {
    for (auto& ans : answers) {
      if (ans.load != l) continue;
      json& lj = sc["results"][ans.result]["loads"][l];
      const auto r = nl.solve(ans.alpha);
      if (!r.converged) {
        lj["same_load_error"] = "reference continuation to alpha " + std::to_string(ans.alpha) + ": " + r.reason;
        ++n_failed;
        continue;
      }
      const std::vector<double> u = problem.gather(nl.solution()).values;
      lj["same_load_rel_l2"] = number_or_null(ref.norms->rel_l2(u, ans.u, d));
      lj["same_load_rel_h1"] = number_or_null(ref.norms->rel_h1(u, ans.u, d));
      lj["same_load_ref_max_u"] = number_or_null(r.max_displacement);
      ++n_ok;
    }
  };
  Setting s = ref_set;
  s.name = "reference (same-load pass)";
  const auto solved = solve_setting(ref_shape, cfg, cases, s, 1, 0.0, prefix, false, after);
  for (std::size_t l = 0; l < solved.loads.size(); ++l)
    if (!solved.loads[l].converged) n_failed += int(std::count_if(answers.begin(), answers.end(),
                                                                    [l](const SameLoad& x) { return x.load == l; }));
  if (!solved.error.empty()) std::cerr << "[study] same-load pass: " << solved.error << "\n";
  for (auto& r : sc["results"]) {
    if (!r.contains("loads")) continue;
    std::vector<double> l2, h1;
    for (const auto& lj : r["loads"])
      if (lj.contains("same_load_rel_l2") && lj["same_load_rel_l2"].is_number()) {
        l2.push_back(lj["same_load_rel_l2"].get<double>());
        h1.push_back(lj["same_load_rel_h1"].get<double>());
      }
    const bool all = l2.size() == r["loads"].size() && !l2.empty();
    r["summary"]["same_load_rel_l2"] = number_or_null(all ? finite_mean(l2) : NAN);
    r["summary"]["same_load_rel_h1"] = number_or_null(all ? finite_mean(h1) : NAN);
  }
  sc["same_load_pass"] = {{"solves", n_ok}, {"failed", n_failed}, {"seconds", number_or_null(core::now_seconds() - t0)}};
  std::cerr << fmt::format("[study] same-load pass: {} reference solves, {} failed, {:.1f} s\n", n_ok, n_failed,
                           core::now_seconds() - t0);
}

}  // namespace hypershape::study::accuracy
