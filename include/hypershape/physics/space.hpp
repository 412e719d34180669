#pragma once
/// The discrete displacement space on a (distributed) DMPlex: vector P1 or P2 Lagrange on
/// straight-sided simplices, with everything the hand-written kernels need precomputed once per
/// mesh: per-cell inverse Jacobians, closure dof indices (local and global), the reference basis
/// at the quadrature points, and the canonical (rank-independent) numbering of the nodes.
#include <petscdmplex.h>

#include <array>
#include <string>
#include <span>
#include <utility>
#include <vector>

#include "hypershape/core/petsc_handle.hpp"

namespace hypershape::physics {

/// A homogeneous essential condition: the closure of the points carrying `label` = 1 is fixed in
/// the listed `components`.
struct EssentialBC {
  std::string label;
  std::vector<PetscInt> components;
};

struct SpaceOptions {
  int degree = 1;             ///< 1 or 2
  int quadrature_degree = 0;  ///< cell rule exactness; 0: 2 * degree - 1
  int facet_quadrature_degree = 0;  ///< boundary rule exactness; 0: 2 * degree + 2
};

/// One boundary facet as the surface integrators see it.
struct FacetView {
  PetscInt point;
  int n_vertices;                      ///< dim
  std::array<std::array<double, 3>, 3> x;  ///< vertex coordinates (dim used)
  std::array<double, 3> normal;        ///< outward unit normal (reference configuration)
  int n_nodes;                         ///< dofs-carrying closure points
  std::array<PetscInt, 6> offset;      ///< local-vector offset of each node's first component
  std::array<std::array<int, 2>, 6> ends;  ///< node at facet vertex a (a, a) or edge mid (a, b)
};

class Space;

/// Adds cell matrices (row-major, n_cell_dofs^2, rows and columns in global_dofs(c) order) to a
/// matrix of the space's sparsity pattern, between its construction and destruction. On one
/// rank, into an assembled SeqAIJ matrix, it adds straight into the CSR values through offsets
/// computed once per pattern (Space keeps them): MatSetValues' column search per entry was 18%
/// of a Random2D factory run (perf; the factorisation was 50%). Otherwise MatSetValues.
class CellMatrixAdder {
 public:
  CellMatrixAdder(const Space& space, Mat J);
  ~CellMatrixAdder();
  CellMatrixAdder(const CellMatrixAdder&) = delete;
  CellMatrixAdder& operator=(const CellMatrixAdder&) = delete;
  void add(PetscInt c, const double* Ke) const;
  /// Zeroes the entries cell c adds to (direct() only).
  void zero(PetscInt c) const;
  /// Whether this adder writes into the CSR values directly.
  bool direct() const { return values_ != nullptr; }

 private:
  const Space& space_;
  Mat J_;
  PetscScalar* values_ = nullptr;  ///< the CSR values (direct path), or null
  const PetscInt* offsets_ = nullptr;
  int n_ = 0;
};

namespace detail {
struct CanonicalIds;  // space.cpp: the canonical node ids of the serial plex
}  // namespace detail

class Space {
 public:
  /// Builds the space on `dm` (distributed or not; takes ownership). `serial` and `migration`
  /// give the canonical node numbering: `serial` is the undistributed plex (all points on rank
  /// 0), `migration` the SF from DMPlexDistribute (empty on one rank). Collective.
  Space(core::DMH dm, DM serial, PetscSF migration, const SpaceOptions& opt,
        const std::vector<EssentialBC>& bcs);

  DM dm() const { return dm_.get(); }
  PetscFE fe() const { return fe_.get(); }
  MPI_Comm comm() const { return PetscObjectComm((PetscObject)dm_.get()); }
  int dim() const { return dim_; }
  int degree() const { return degree_; }
  int n_nodes() const { return n_nodes_; }  ///< nodes per cell (3/6 in 2D, 4/10 in 3D)
  int n_cell_dofs() const { return n_nodes_ * dim_; }
  PetscInt cell_begin() const { return c0_; }
  PetscInt cell_end() const { return c1_; }
  /// The cells the assembly loops visit, in order: every local cell, or the subset a
  /// CellSubset has made active (a local solve's patch: src/solver/local_relaxation.cpp).
  std::span<const PetscInt> cells() const { return subset_ ? *subset_ : std::span<const PetscInt>(all_cells_); }
  /// Whether a CellSubset is active.
  bool restricted() const { return subset_ != nullptr; }
  std::int64_t n_cells_global() const { return n_cells_global_; }
  std::int64_t n_dofs_global() const { return n_dofs_global_; }  ///< unconstrained dofs
  std::int64_t n_vertices_global() const { return n_vertices_global_; }
  std::int64_t n_nodes_global() const { return n_nodes_global_; }

  // Cell rule on the reference simplex [-1,1]^d.
  int n_qp() const { return n_qp_; }
  double qweight(int q) const { return qw_[q]; }
  double basis(int q, int a) const { return N_[q * n_nodes_ + a]; }
  /// Reference gradient d N_a / d xi_k at point q.
  const double* ref_grad(int q) const { return &dN_[std::size_t(q) * n_nodes_ * dim_]; }
  /// Row-major d xi / d x of cell c (dim x dim) and det(d x / d xi).
  const double* inv_jacobian(PetscInt c) const { return &invJ_[std::size_t(c - c0_) * dim_ * dim_]; }
  double det_jacobian(PetscInt c) const { return detJ_[c - c0_]; }
  /// Physical point of reference point q in cell c.
  void map_point(PetscInt c, int q, double* x) const;
  /// Local-vector offsets of the cell's dofs (node-major, components contiguous).
  const PetscInt* local_dofs(PetscInt c) const { return &ldofs_[std::size_t(c - c0_) * n_cell_dofs()]; }
  /// Global indices for MatSetValues (constrained dofs negative: dropped).
  const PetscInt* global_dofs(PetscInt c) const { return &gdofs_[std::size_t(c - c0_) * n_cell_dofs()]; }

  /// Boundary facets owned here that carry no essential label (the Neumann boundary).
  const std::vector<FacetView>& neumann_facets() const { return neumann_facets_; }
  /// Facet rule on the reference simplex of dimension dim-1, as barycentric coordinates.
  int n_facet_qp() const { return int(fqw_.size()); }
  double facet_qweight(int q) const { return fqw_[q]; }  ///< sums to 1 (scale by facet measure)
  const double* facet_bary(int q) const { return &fbary_[std::size_t(q) * dim_]; }
  /// Value of facet node `ends` at barycentric `bary` (P1: lambda_a; P2: quadratic).
  double facet_basis(const std::array<int, 2>& ends, const double* bary) const;
  static double facet_measure(const FacetView& f, int dim);
  /// Coordinates of the node carried by plex point p (a vertex, or the midpoint of an edge for
  /// P2), from the coordinate section `cs` and local coordinate array `xa`.
  static std::array<double, 3> node_coords(DM dm, PetscSection cs, const PetscScalar* xa,
                                           PetscInt p, int dim);

  /// Owned dof-carrying points: local offset, canonical node id, coordinates. Each node of the
  /// mesh is owned by exactly one rank.
  struct OwnedNode {
    PetscInt offset;
    std::int64_t canonical;
    std::array<double, 3> x;
  };
  const std::vector<OwnedNode>& owned_nodes() const { return owned_nodes_; }
  /// Canonical cell-to-node connectivity (VTK/XDMF order, P1 or P2), significant on rank 0.
  const std::vector<std::int64_t>& canonical_cells() const { return canonical_cells_; }
  /// Canonical node coordinates (n_nodes_global x dim), significant on rank 0.
  const std::vector<double>& canonical_coords() const { return canonical_coords_; }

  /// Minimum over all cells of det(d x / d xi) (collective).
  double min_det_jacobian() const;

  /// A matrix for the tangent with its whole pattern (every pair of free dofs that share a cell),
  /// values zero: DMCreateMatrix's matrix. On one rank the pattern comes from the cells' global
  /// dofs (DMPlexPreallocateOperator's adjacency search was 130 ms per refined 2D P1 mesh of the
  /// error estimate); on more ranks, DMCreateMatrix's own. Collective.
  core::MatH create_matrix() const;

 private:
  friend class CellMatrixAdder;
  // The constructor's steps, in order.
  void create_fe(const SpaceOptions& opt, const std::vector<EssentialBC>& bcs, core::QuadH& q, core::QuadH& fq);
  void tabulate_cell_rule(PetscQuadrature q);
  void tabulate_facet_rule(PetscQuadrature fq);
  void build_cells();
  void cell_dofs(PetscInt c, PetscSection ls, PetscSection gs);
  void collect_neumann_facets(const std::vector<EssentialBC>& bcs, PetscSection cs, const PetscScalar* xa);
  void number_nodes(DM serial, PetscSF migration, PetscSection cs, const PetscScalar* xa);
  void build_output_mesh(DM serial, const detail::CanonicalIds& canonical);

  /// Offsets into the CSR values of the assembled SeqAIJ matrix J of every cell-matrix entry
  /// (-1: a constrained dof), rebuilt when a matrix of another pattern comes; empty where a cell
  /// entry is not in J's pattern.
  const std::vector<PetscInt>& csr_offsets(Mat J) const;
  bool build_csr_offsets(const PetscInt* ia, const PetscInt* ja, PetscInt n) const;  ///< false: not in the pattern
  mutable std::vector<PetscInt> csr_ia_, csr_ja_, csr_offsets_;
  /// The matrices (object id, nonzero state) whose pattern was found to be csr_ia_ / csr_ja_: a
  /// tangent assembly then skips comparing the pattern (a memcmp of it was 0.7% of a P2 run).
  mutable std::vector<std::pair<PetscInt64, PetscObjectState>> csr_matrices_;

  core::DMH dm_;
  core::FEH fe_;
  int dim_ = 0, degree_ = 1, n_nodes_ = 0, n_qp_ = 0;
  PetscInt c0_ = 0, c1_ = 0;
  std::vector<PetscInt> all_cells_;  ///< c0_, ..., c1_ - 1
  friend class CellSubset;
  mutable const std::vector<PetscInt>* subset_ = nullptr;  ///< CellSubset's cells, or null
  std::int64_t n_cells_global_ = 0, n_dofs_global_ = 0, n_vertices_global_ = 0,
               n_nodes_global_ = 0;
  std::vector<double> qw_, N_, dN_, qxi_;
  std::vector<double> invJ_, detJ_, v0_;
  std::vector<PetscInt> ldofs_, gdofs_;
  std::vector<FacetView> neumann_facets_;
  std::vector<double> fqw_, fbary_;
  std::vector<OwnedNode> owned_nodes_;
  std::vector<std::int64_t> canonical_cells_;
  std::vector<double> canonical_coords_;
};

/// While it lives, the assembly loops of `space` (Space::cells) visit only `cells` (sorted, local
/// cell numbers): the energy, residual and tangent of a patch, exact at the dofs whose cells all
/// lie in it (on one rank the tangent's other entries keep what they held: Problem::jacobian
/// zeroes only the entries the patch's cells add to). Not nested; not collective.
class CellSubset {
 public:
  CellSubset(const Space& space, const std::vector<PetscInt>& cells) : space_(space) { space_.subset_ = &cells; }
  ~CellSubset() { space_.subset_ = nullptr; }
  CellSubset(const CellSubset&) = delete;
  CellSubset& operator=(const CellSubset&) = delete;

 private:
  const Space& space_;
};

}  // namespace hypershape::physics
