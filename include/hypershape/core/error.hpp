#pragma once
/// Error types and the PETSc call wrapper.
///
/// A bug is an `assert`; bad input is an `InputError` that names the file and the key; a failing
/// PETSc call becomes a `PetscError` carrying the call text. Numerical failures of a load case
/// are *not* exceptions: they are recorded outcomes (see solver/).
#include <petscsys.h>

#include <stdexcept>
#include <string>

#include "hypershape/core/input_error.hpp"

namespace hypershape::core {

/// A PETSc call returned a non-zero error code.
class PetscError : public std::runtime_error {
 public:
  PetscError(PetscErrorCode code, const char* call, const char* file, int line);
  PetscErrorCode code() const { return code_; }

 private:
  PetscErrorCode code_;
};

/// Throws `PetscError` if `code` is non-zero. Use through HS_PETSC.
inline void check_petsc(PetscErrorCode code, const char* call, const char* file, int line) {
  if (code) throw PetscError(code, call, file, line);
}

}  // namespace hypershape::core

/// Calls a PETSc function and throws hypershape::core::PetscError (with the call text) on failure.
#define HS_PETSC(call) ::hypershape::core::check_petsc((call), #call, __FILE__, __LINE__)
