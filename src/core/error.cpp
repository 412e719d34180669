#include "hypershape/core/error.hpp"

#include <fmt/format.h>

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

PetscError::PetscError(PetscErrorCode code, const char* call, const char* file, int line)
    : std::runtime_error(fmt::format("PETSc error {} in `{}` ({}:{})", static_cast<int>(code), call,
                                     file, line)),
      code_(code) {}

}  // namespace hypershape::core
