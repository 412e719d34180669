#pragma once
/// The two array guards of the project (no VecGetArray without its Restore anywhere else):
/// VecArray for a Vec's array in one scope, LocalArray for a DM's borrowed local vector and
/// its array.
///
/// A Vec's array for one scope: VecGetArray(Read) on construction, VecRestoreArray(Read) on
/// destruction (also when an exception leaves the scope), so no Get can miss its Restore.
///   core::VecArray<const PetscScalar> x(u);   // read
///   core::VecArray<PetscScalar> y(v);         // read and write
///   y[i] = 2 * x[i];
#include <petscdm.h>
#include <petscvec.h>

#include <type_traits>

#include "hypershape/core/error.hpp"

namespace hypershape::core {

template <class T>
class VecArray {
  static_assert(std::is_same_v<std::remove_const_t<T>, PetscScalar>);
  static constexpr bool kRead = std::is_const_v<T>;

 public:
  explicit VecArray(Vec v) : v_(v) {
    if constexpr (kRead) HS_PETSC(VecGetArrayRead(v_, &a_));
    else HS_PETSC(VecGetArray(v_, &a_));
  }
  ~VecArray() {
    if constexpr (kRead) VecRestoreArrayRead(v_, &a_);
    else VecRestoreArray(v_, &a_);
  }
  VecArray(const VecArray&) = delete;
  VecArray& operator=(const VecArray&) = delete;

  T* data() const { return a_; }
  T& operator[](PetscInt i) const { return a_[i]; }

 private:
  Vec v_;
  T* a_ = nullptr;
};

/// A borrowed local vector of a DM (DMGetLocalVector / DMRestoreLocalVector) with its array
/// taken on first use and given back by release() or on scope exit. `write` zeroes the vector
/// (for accumulation) and takes the array read-write; otherwise the array is read-only.
///   core::LocalArray ul(dm, false);
///   to_local(u, ul.vec());             // fill the vector before taking its array
///   kernel(ul.array());
class LocalArray {
 public:
  LocalArray(DM dm, bool write) : dm_(dm), write_(write) {
    HS_PETSC(DMGetLocalVector(dm, &v_));
    if (write) HS_PETSC(VecZeroEntries(v_));
  }
  ~LocalArray() {
    release();
    DMRestoreLocalVector(dm_, &v_);
  }
  LocalArray(const LocalArray&) = delete;
  LocalArray& operator=(const LocalArray&) = delete;

  Vec vec() const { return v_; }
  /// The array (taken now if not yet): read-write if `write`, else only to be read.
  PetscScalar* array() {
    if (!a_) {
      if (write_) HS_PETSC(VecGetArray(v_, &a_));
      else HS_PETSC(VecGetArrayRead(v_, const_cast<const PetscScalar**>(&a_)));
    }
    return a_;
  }
  /// Gives the array back (before the vector is used as a whole, e.g. DMLocalToGlobal).
  void release() {
    if (!a_) return;
    if (write_) VecRestoreArray(v_, &a_);
    else VecRestoreArrayRead(v_, const_cast<const PetscScalar**>(&a_));
    a_ = nullptr;
  }

 private:
  DM dm_;
  bool write_;
  Vec v_ = nullptr;
  PetscScalar* a_ = nullptr;
};

}  // namespace hypershape::core
