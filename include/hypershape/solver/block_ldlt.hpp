#pragma once
/// U^T D U of a symmetric matrix of 2x2 blocks (one per node of a 2D vector field), without
/// pivoting: the numeric factorisation and the solves of the blocked LDL^T (ldlt.hpp).
///
/// The arithmetic is PETSc 3.18's for block size 2 in the natural ordering (SBAIJ, "up-looking":
/// row k of U from the rows above it, taken in the same order, each 2x2 product summed in the
/// same order, D_k inverted by PETSc's own 2x2 kernel), so the factor and its solutions are the
/// same to the bit. What differs is how it runs: each 2x2 block update is two 2-lane vector
/// operations (one IEEE operation per lane, in the scalar code's order: the same numbers on
/// every x86-64 machine) where PETSc's compiled kernel does eight scalar ones, and the pattern
/// of U is computed once per problem rather than at every factorisation's set-up.
#include <petscsys.h>

#include <cstddef>
#include <new>
#include <vector>

namespace hypershape::solver {

/// An allocator on 64-byte boundaries (a cache line): the factor's 2x2 blocks (32 bytes) are
/// then each within one line, where malloc's 16-byte alignment splits every other one.
template <class T>
struct CacheLineAllocator {
  using value_type = T;
  CacheLineAllocator() = default;
  template <class U>
  CacheLineAllocator(const CacheLineAllocator<U>&) noexcept {}
  T* allocate(std::size_t n) { return static_cast<T*>(::operator new(n * sizeof(T), std::align_val_t{64})); }
  void deallocate(T* p, std::size_t) noexcept { ::operator delete(p, std::align_val_t{64}); }
  friend bool operator==(CacheLineAllocator, CacheLineAllocator) { return true; }
};
using AlignedDoubles = std::vector<double, CacheLineAllocator<double>>;

/// Negative eigenvalues of a block-diagonal D given by its nb inverted 2x2 blocks (4 each,
/// column-major, as PETSc's blocked factor and BlockLdlt2 store them): a block and its inverse
/// have the same inertia (Sylvester's law: the matrix's).
int negative_eigenvalues_2x2(const PetscScalar* dinv, PetscInt nb);

class BlockLdlt2 {
 public:
  /// The upper block pattern of the matrix: rows `nb`, row k's block columns
  /// cols[rows[k] .. rows[k+1]), ascending, the diagonal first. Computes the pattern of U.
  void analyse(PetscInt nb, const PetscInt* rows, const PetscInt* cols);
  /// Factorises the values of that pattern (4 per block, column-major: SBAIJ's layout). False
  /// on a zero pivot (the factor is then unusable).
  bool factorise(const PetscScalar* values);
  /// x = A^-1 x for the matrix last factorised (x: 2 nb entries).
  void solve(PetscScalar* x) const;
  /// Two right-hand sides at once, interleaved by node: x = (a_k0, a_k1, b_k0, b_k1) for node k
  /// (4 nb entries). Each one's numbers are solve()'s; U is read once for both.
  void solve2(PetscScalar* x) const;
  /// Negative eigenvalues of the matrix last factorised (Sylvester: those of D).
  int negative_eigenvalues() const;
  /// solve2 with U^T |D| U (each 2x2 block of D with its eigenvalues made positive).
  void solve2_absolute(PetscScalar* x) const;
  PetscInt blocks() const { return nb_; }
  /// Blocks of U (strictly upper), for the flop count.
  std::size_t factor_blocks() const { return uj_.size(); }

 private:
  PetscInt nb_ = 0;
  std::vector<PetscInt> ai_, aj_;  ///< the matrix's upper block pattern
  std::vector<PetscInt> ui_, uj_;  ///< U's strictly upper block pattern (rows, columns)
  AlignedDoubles d_;               ///< D_k^-1, 4 per row, column-major
  mutable AlignedDoubles dabs_;    ///< |D_k|^-1 (solve2_absolute), made from d_ on demand
  mutable bool dabs_current_ = false;
  AlignedDoubles u_;               ///< U's blocks, 4 each, column-major
  // Work arrays of the factorisation: a dense block row, and the linked lists of the rows
  // that update the row being factorised (next_[i]) and where row i's next block is (first_[i]).
  AlignedDoubles row_;
  std::vector<PetscInt> next_, first_;
};

}  // namespace hypershape::solver
