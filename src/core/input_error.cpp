#include "hypershape/core/input_error.hpp"

namespace hypershape::core {

namespace {
std::string input_message(const std::string& file, const std::string& key,
                          const std::string& message) {
  std::string s;
  if (!file.empty()) s += file + ": ";
  if (!key.empty()) s += key + ": ";
  return s + message;
}
}  // namespace

InputError::InputError(std::string file, std::string key, const std::string& message)
    : std::runtime_error(input_message(file, key, message)),
      file_(std::move(file)),
      key_(std::move(key)) {}

}  // namespace hypershape::core
