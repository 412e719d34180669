#pragma once
/// Bad user input, without any PETSc dependency (modules such as geometry/ use it).
#include <stdexcept>
#include <string>

namespace hypershape::core {

/// Bad user input (scene/config file, mesh file, options). `what()` reads
/// "<file>: <key>: <message>"; `file` or `key` may be empty when not applicable.
class InputError : public std::runtime_error {
 public:
  InputError(std::string file, std::string key, const std::string& message);
  const std::string& file() const { return file_; }
  const std::string& key() const { return key_; }

 private:
  std::string file_, key_;
};

}  // namespace hypershape::core
