// The markdown tables of the accuracy study.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <tuple>

#include "accuracy_detail.hpp"
#include "hypershape/core/timer.hpp"
#include "hypershape/study/stats.hpp"

namespace hypershape::study::accuracy {

std::string fmt_e(const json& v) { return v.is_null() ? "-" : fmt::format("{:.2e}", v.get<double>()); }
std::string fmt_s(const json& v) {
  if (v.is_null()) return "-";
  const double s = v.get<double>();
  return s < 1 ? fmt::format("{:.0f} ms", s * 1e3) : fmt::format("{:.2f} s", s);
}

void print_table(std::ostream& os, const json& out) {
  for (const auto& sc : out["scenes"]) {
    os << fmt::format("\n### {} ({}D, {} shape {})\n\n", sc["name"].get<std::string>(), sc.value("dim", 0),
                      sc["preset"].get<std::string>(), sc["shape_id"].get<long>());
    if (sc.contains("error")) {
      os << "error: " << sc["error"].get<std::string>() << "\n";
      continue;
    }
    const auto& ref = sc["reference"];
    os << fmt::format("reference: P2 h {} ({} DoFs), estimated own error rel L2 {} / H1 {} / alpha {}\n\n",
                      ref["h"].get<double>(), ref["dofs"].get<long>(), fmt_e(ref["richardson_l2_mean"]),
                      fmt_e(ref["richardson_h1_mean"]), fmt_e(ref["richardson_alpha_mean"]));
    os << "| setting | DoFs | time/load | rel L2 | rel H1 | alpha err | same-load L2 | solver err | peak RSS +MiB | ok |\n"
          "|---|---|---|---|---|---|---|---|---|---|\n";
    for (const auto& r : sc["results"]) {
      const auto& m = r["summary"];
      os << fmt::format("| {}{} | {} | {} | {} | {} | {} | {} | {} | {} | {}/{} |\n",
                        r["setting"]["name"].get<std::string>(), r["setting"]["is_default"].get<bool>() ? " (default)" : "",
                        r.value("dofs", json(0)).get<long>(), fmt_s(m["seconds_per_load"]), fmt_e(m["rel_l2"]),
                        fmt_e(m["rel_h1"]), fmt_e(m["alpha_err"]), fmt_e(m.value("same_load_rel_l2", json())),
                        fmt_e(m["solver_l2"]),
                        r["peak_rss_delta_mib"].is_null() ? "-" : fmt::format("{:.0f}", r["peak_rss_delta_mib"].get<double>()),
                        m["converged"].get<int>(), m["loads"].get<int>());
    }
  }
}

}  // namespace hypershape::study::accuracy
