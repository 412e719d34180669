// The accuracy study's settings: a config's mesh.quadrature (the study's --override) becomes every
// setting's cell rule and the baseline's, and names the h x degree grid; without it, the default.
// (The references keep the default: reference_setting sets no quadrature.)
#include <catch2/catch.hpp>

#include "../../src/study/accuracy_detail.hpp"
#include "hypershape/config/dataset.hpp"

using namespace hypershape;
using namespace hypershape::study::accuracy;

TEST_CASE("study settings take the config's mesh.quadrature, references aside", "[study][settings]") {
  study::AccuracyOptions a;
  a.tiny = true;
  for (const int q : {0, 2}) {
    CAPTURE(q);
    const auto cfg = config::parse_dataset_text(
        std::string("preset: random2d_p1\n") + (q ? "mesh: {quadrature: 2}\n" : ""), "<test>");
    const auto settings = make_settings(2, a, cfg, 0.02, SceneKind::disk);
    REQUIRE(!settings.empty());
    int baselines = 0;
    for (const auto& s : settings) {
      CHECK(s.quadrature == q);
      CHECK(setting_json(s)["quadrature_degree"] == (q ? q : 2 * s.degree - 1));
      if (s.group == "mesh") CHECK((s.name.find("quad 2") != std::string::npos) == (q == 2));
      baselines += s.baseline_discretisation;
    }
    CHECK(baselines >= 1);  // the tight-tolerance yardstick still has its baseline
  }
}
