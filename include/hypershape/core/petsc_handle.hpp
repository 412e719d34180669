#pragma once
/// Move-only RAII owners of PETSc objects and the PETSc session guard.
#include <petscdm.h>
#include <petscdmlabel.h>
#include <petscfe.h>
#include <petscis.h>
#include <petscmat.h>
#include <petscsf.h>
#include <petscsnes.h>
#include <petscvec.h>

#include <utility>

namespace hypershape::core {

/// Owns one reference of a PETSc object; the destructor calls `XDestroy`.
template <class T, PetscErrorCode (*Destroy)(T*)>
class Handle {
 public:
  Handle() = default;
  explicit Handle(T obj) : obj_(obj) {}
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  Handle(Handle&& o) noexcept : obj_(std::exchange(o.obj_, nullptr)) {}
  Handle& operator=(Handle&& o) noexcept {
    if (this != &o) {
      reset();
      obj_ = std::exchange(o.obj_, nullptr);
    }
    return *this;
  }
  ~Handle() { reset(); }

  void reset() {
    if (obj_) Destroy(&obj_);
    obj_ = nullptr;
  }
  T get() const { return obj_; }
  operator T() const { return obj_; }  // NOLINT: PETSc calls take the raw object.
  /// For PETSc "create" calls: `VecCreate(comm, v.out())`. Releases what was held.
  T* out() {
    reset();
    return &obj_;
  }
  T release() { return std::exchange(obj_, nullptr); }
  explicit operator bool() const { return obj_ != nullptr; }

 private:
  T obj_ = nullptr;
};

using VecH = Handle<Vec, VecDestroy>;
using MatH = Handle<Mat, MatDestroy>;
using DMH = Handle<DM, DMDestroy>;
using SNESH = Handle<SNES, SNESDestroy>;
using KSPH = Handle<KSP, KSPDestroy>;
using ISH = Handle<IS, ISDestroy>;
using SFH = Handle<PetscSF, PetscSFDestroy>;
using FEH = Handle<PetscFE, PetscFEDestroy>;
using QuadH = Handle<PetscQuadrature, PetscQuadratureDestroy>;
using LabelH = Handle<DMLabel, DMLabelDestroy>;

/// PetscInitialize/PetscFinalize as a scope guard; create it first in `main`.
class PetscSession {
 public:
  PetscSession(int* argc, char*** argv, const char* help);
  PetscSession(const PetscSession&) = delete;
  PetscSession& operator=(const PetscSession&) = delete;
  ~PetscSession();
};

/// MPI rank and size of a communicator.
int rank(MPI_Comm comm);
int size(MPI_Comm comm);

}  // namespace hypershape::core
