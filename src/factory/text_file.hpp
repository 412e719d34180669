#pragma once
/// Small text-file helpers of the factory (internal): whole-file reads, and writes that appear
/// atomically (temporary name with the pid, then rename), so a reader never sees half a file.
#include <fmt/format.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

namespace hypershape::factory::detail {

inline std::string read_text(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

inline void write_atomically(const std::filesystem::path& path, const std::string& text) {
  const std::filesystem::path tmp = path.string() + fmt::format(".tmp-{}", ::getpid());
  {
    std::ofstream o(tmp);
    o << text;
    if (!o) throw std::runtime_error("cannot write " + tmp.string());
  }
  std::filesystem::rename(tmp, path);
}

}  // namespace hypershape::factory::detail
