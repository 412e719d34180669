#pragma once
/// A Vec's array for one scope: VecGetArray(Read) on construction, VecRestoreArray(Read) on
/// destruction (also when an exception leaves the scope), so no Get can miss its Restore.
///   core::VecArray<const PetscScalar> x(u);   // read
///   core::VecArray<PetscScalar> y(v);         // read and write
///   y[i] = 2 * x[i];
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

}  // namespace hypershape::core
