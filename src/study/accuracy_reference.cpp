// The reference of a scene of the accuracy study, its Richardson estimate, and the metrics
// against it.
#include <fmt/format.h>

#include <cmath>
#include <iostream>

#include "accuracy_detail.hpp"
#include "hypershape/core/timer.hpp"
#include "hypershape/sampling/mesh_sampler.hpp"
#include "hypershape/study/stats.hpp"

namespace hypershape::study::accuracy {

std::vector<std::vector<double>> at_reference(const factory::ShapeSample& shape, const SolvedSetting& s,
                                              const Reference& ref, int d) {
  sampling::MeshSampler sampler(d, s.nodes_per_cell == d + 1 ? 1 : 2, s.nodes, s.cells, shape.boundary, ref.nodes);
  std::vector<std::vector<double>> out;
  for (const auto& lo : s.loads) out.push_back(lo.converged ? sampler.interpolate(lo.u, d) : std::vector<double>{});
  return out;
}

namespace {

std::vector<double> difference(const std::vector<double>& a, const std::vector<double>& b) {
  std::vector<double> diff(a.size());
  for (std::size_t i = 0; i < a.size(); ++i) diff[i] = a[i] - b[i];
  return diff;
}

double rel_h1_diff(const sampling::NodalNorms& nn, const std::vector<double>& a, const std::vector<double>& b,
                   const std::vector<double>& ref, int d) {
  return nn.h1_norm(difference(a, b), d) / nn.h1_norm(ref, d);
}

/// Richardson: the observed order from the differences of consecutive levels and the error of
/// the finest. d1 = |finest - next|, d2 = |next - coarsest| (d2 NaN with two levels).
json richardson(double d1, double d2) {
  json r;
  r["d1"] = number_or_null(d1);
  r["d2"] = number_or_null(d2);
  double p = NAN;
  bool assumed = false;
  if (std::isfinite(d2) && d1 > 0 && d2 > 0) p = std::log2(d2 / d1);
  double pu = p;
  if (!std::isfinite(p)) {
    pu = 1.0;
    assumed = true;
  }
  const bool clamped = std::isfinite(p) && (p < 0.5 || p > 4.0);
  pu = std::clamp(pu, 0.5, 4.0);
  r["order_observed"] = number_or_null(p);
  r["order_used"] = pu;
  r["order_assumed"] = assumed;
  r["order_clamped"] = clamped;
  r["estimate"] = number_or_null(d1 / (std::pow(2.0, pu) - 1.0));
  return r;
}

/// The reference's solves, level by level (level 0: the reference itself).
struct Ladder {
  std::vector<std::vector<std::vector<double>>> u;  // level -> load -> field at ref nodes
  std::vector<std::vector<double>> alpha;           // level -> load
  json record = json::array();
};

/// The reference's own fields and record from its solve (ladder level 0).
void take_reference(const Scene& s, const factory::ShapeSample& shape, const SolvedSetting& solved, Reference& ref) {
  ref.nodes = solved.nodes;
  ref.cells = solved.cells;
  ref.nodes_per_cell = solved.nodes_per_cell;
  ref.norms = std::make_unique<sampling::NodalNorms>(s.d, ref.nodes, ref.cells, ref.nodes_per_cell);
  ref.sdf = std::make_unique<geometry::SignedDistance>(shape.boundary);
  for (auto& lo : solved.loads) {
    ref.u.push_back(lo.u);
    ref.alpha.push_back(lo.alpha);
  }
  ref.record["dofs"] = solved.dofs;
  ref.record["vertices"] = solved.n_vertices;
  ref.record["nodes"] = ref.nodes.size() / std::size_t(s.d);
  ref.record["alpha"] = ref.alpha;
  ref.record["dirichlet_center"] = shape.dirichlet_center;
}

json ladder_record(const Scene& s, double h, const SolvedSetting& solved) {
  json lj;
  lj["h"] = h;
  lj["dofs"] = solved.dofs;
  lj["linear_solver"] = solved.linear_solver;
  lj["vertices"] = solved.n_vertices;
  lj["seconds_mesh"] = number_or_null(s.shapes->seconds(h, true));
  lj["seconds_setup"] = number_or_null(solved.seconds_setup);
  lj["peak_rss_mib"] = number_or_null(solved.peak_rss_mib);
  lj["peak_rss_delta_mib"] = number_or_null(solved.peak_rss_mib - solved.rss_before_mib);
  json per = json::array();
  for (const auto& lo : solved.loads)
    per.push_back({{"converged", lo.converged}, {"reason", lo.reason}, {"alpha", number_or_null(lo.alpha)},
                   {"max_u", number_or_null(lo.max_u)}, {"seconds", number_or_null(lo.seconds)},
                   {"newton", lo.newton}});
  lj["loads"] = per;
  return lj;
}

/// Solves ladder level `level` (h = ref_h 2^level) into `lj`; throws if it fails.
void solve_level(Scene& s, Setting ref_set, int level, Reference& ref, Ladder& ladder, json& lj) {
  const double h = lj["h"].get<double>();
  ref_set.h = h;
  ref_set.name = fmt::format("reference P2 h{}", fmt_g(h));
  const auto& shape = s.shapes->at(h, true);
  check_same_draw(shape, *s.base_shape, h);
  auto solved = solve_setting(shape, s.cfg, s.cases, ref_set, 1, 0.0, fmt::format("s{}_", s.setting_counter++), true);
  if (!solved.error.empty()) throw std::runtime_error(solved.error);
  lj = ladder_record(s, h, solved);
  for (const auto& lo : solved.loads)
    if (!lo.converged) throw std::runtime_error("a reference load case failed: " + lo.reason);
  if (level == 0) {
    take_reference(s, shape, solved, ref);
    ladder.u.push_back(ref.u);
  } else {
    ladder.u.push_back(at_reference(shape, solved, ref, s.d));
  }
  std::vector<double> al;
  for (auto& lo : solved.loads) al.push_back(lo.alpha);
  ladder.alpha.push_back(al);
}

/// Every level of the ladder, until one fails (the levels must be consecutive; level 0 must not fail).
Ladder solve_ladder(Scene& s, const Setting& ref_set, Reference& ref) {
  Ladder ladder;
  for (int level = 0; level < s.n_levels; ++level) {
    const double h = s.ref_h * std::pow(2.0, level);
    const double t0 = core::now_seconds();
    json lj;
    lj["h"] = h;
    try {
      solve_level(s, ref_set, level, ref, ladder, lj);
    } catch (const std::exception& e) {
      if (level == 0) throw;
      lj["error"] = e.what();
      std::cerr << fmt::format("[study] {}: ladder level h {} failed: {}\n", s.spec.name, h, e.what());
      ladder.record.push_back(lj);
      break;
    }
    lj["seconds_total"] = core::now_seconds() - t0;
    std::cerr << fmt::format("[study] {}: reference ladder P2 h {}: {} DoFs, {:.1f} s\n", s.spec.name, h,
                             lj.value("dofs", json(0)).get<long>(), lj["seconds_total"].get<double>());
    ladder.record.push_back(lj);
  }
  return ladder;
}

/// The Richardson estimate of load case l, for L2, H1 and alpha.
json richardson_of_load(const Reference& ref, const Ladder& ladder, std::size_t l, int d) {
  const auto& u0 = ref.u[l];
  const auto& lu = ladder.u;
  const auto& la = ladder.alpha;
  double d1l2 = NAN, d2l2 = NAN, d1h1 = NAN, d2h1 = NAN, d1a = NAN, d2a = NAN;
  if (lu.size() >= 2) {
    d1l2 = rel_l2_diff(lu[1][l], u0, u0, d);
    d1h1 = rel_h1_diff(*ref.norms, lu[1][l], u0, u0, d);
    d1a = std::abs(la[1][l] - la[0][l]) / la[0][l];
  }
  if (lu.size() >= 3) {
    d2l2 = rel_l2_diff(lu[2][l], lu[1][l], u0, d);
    d2h1 = rel_h1_diff(*ref.norms, lu[2][l], lu[1][l], u0, d);
    d2a = std::abs(la[2][l] - la[1][l]) / la[0][l];
  }
  return {{"l2", richardson(d1l2, d2l2)}, {"h1", richardson(d1h1, d2h1)}, {"alpha", richardson(d1a, d2a)}};
}

double estimate(const json& r) { return r["estimate"].is_null() ? NAN : r["estimate"].get<double>(); }

void add_richardson(const Scene& s, const Ladder& ladder, Reference& ref) {
  json rich = json::array();
  std::vector<double> est_l2, est_h1, est_alpha;
  for (std::size_t l = 0; l < s.cases.size(); ++l) {
    json rj = richardson_of_load(ref, ladder, l, s.d);
    est_l2.push_back(estimate(rj["l2"]));
    est_h1.push_back(estimate(rj["h1"]));
    est_alpha.push_back(estimate(rj["alpha"]));
    rich.push_back(rj);
  }
  ref.record["richardson"] = rich;
  ref.record["richardson_l2_mean"] = number_or_null(finite_mean(est_l2));
  ref.record["richardson_h1_mean"] = number_or_null(finite_mean(est_h1));
  ref.record["richardson_alpha_mean"] = number_or_null(finite_mean(est_alpha));
  std::cerr << fmt::format("[study] {}: reference P2 h {}: estimated own error rel L2 {:.2e}, H1 {:.2e}, "
                           "alpha {:.2e} (Richardson, order {})\n",
                           s.spec.name, s.ref_h, finite_mean(est_l2), finite_mean(est_h1), finite_mean(est_alpha),
                           rich[0]["l2"]["order_used"].get<double>());
}

}  // namespace

double rel_l2_diff(const std::vector<double>& a, const std::vector<double>& b, const std::vector<double>& ref, int d) {
  return sampling::discrete_l2_norm(difference(a, b), d) / sampling::discrete_l2_norm(ref, d);
}

Setting reference_setting(const Scene& s) {
  Setting ref_set;
  ref_set.degree = 2;
  ref_set.opt = s.cfg.solver;
  ref_set.opt.rtol = 1e-10;
  ref_set.opt.target_rtol = 1e-6;
  ref_set.petsc = mumps_cholesky();
  return ref_set;
}

Reference build_reference(Scene& s, const Setting& ref_set) {
  Reference ref;
  ref.h = s.ref_h;
  const Ladder ladder = solve_ladder(s, ref_set, ref);
  ref.record["h"] = s.ref_h;
  ref.record["graded"] = s.spec.kind == SceneKind::disk && s.a.ref_grading < 1.0;
  ref.record["grading_end_fraction"] = ref.record["graded"].get<bool>() ? s.a.ref_grading : 1.0;
  ref.record["degree"] = 2;
  ref.record["ladder"] = ladder.record;
  add_richardson(s, ladder, ref);
  return ref;
}

}  // namespace hypershape::study::accuracy
