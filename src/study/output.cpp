#include "hypershape/study/output.hpp"

#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>

#include "hypershape/core/input_error.hpp"

namespace hypershape::study {

SplitArgs split_at_dashes(int argc, char** argv) {
  SplitArgs s;
  s.ours.push_back(argv[0]);
  s.petsc.push_back(argv[0]);
  bool after = false;
  for (int i = 1; i < argc; ++i) {
    if (!after && std::string(argv[i]) == "--") {
      after = true;
      continue;
    }
    (after ? s.petsc : s.ours).push_back(argv[i]);
  }
  return s;
}

bool output_writable(const std::string& path, const std::string& option) {
  if (path.empty()) return true;
  const std::filesystem::path p(path);
  std::error_code ec;
  if (p.has_parent_path()) std::filesystem::create_directories(p.parent_path(), ec);
  const std::string tmp = path + ".tmp";
  if (!std::ofstream(tmp)) {
    std::cerr << "error: " << path << ": " << option << ": cannot open for writing\n";
    return false;
  }
  std::filesystem::remove(tmp, ec);
  return true;
}

void write_json_atomic(const std::string& path, const nlohmann::json& j, const std::string& option, int indent) {
  const std::filesystem::path p(path);
  if (p.has_parent_path()) std::filesystem::create_directories(p.parent_path());
  const std::string tmp = path + ".tmp";
  {
    std::ofstream f(tmp);
    if (!f) throw core::InputError(path, option, "cannot open for writing");
    f << j.dump(indent) << "\n";
  }
  std::filesystem::rename(tmp, path);
}

std::string format_seconds(double s) {
  if (!std::isfinite(s)) return "-";
  if (s < 1e-3) return fmt::format("{:.0f}us", s * 1e6);
  if (s < 1.0) return fmt::format("{:.1f}ms", s * 1e3);
  if (s < 100.0) return fmt::format("{:.2f}s", s);
  return fmt::format("{:.0f}s", s);
}

std::string format_count(double v) {
  return std::isfinite(v) ? fmt::format("{}", static_cast<long long>(std::llround(v))) : "-";
}

}  // namespace hypershape::study
