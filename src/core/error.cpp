#include "hypershape/core/error.hpp"

#include <fmt/format.h>

namespace hypershape::core {

PetscError::PetscError(PetscErrorCode code, const char* call, const char* file, int line)
    : std::runtime_error(fmt::format("PETSc error {} in `{}` ({}:{})", static_cast<int>(code), call,
                                     file, line)),
      code_(code) {}

}  // namespace hypershape::core
