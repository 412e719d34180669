#include "hypershape/physics/space.hpp"
#include "hypershape/mesh/reference_cell.hpp"

#include <petscds.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cstring>
#include <numeric>
#include <stdexcept>

#include "hypershape/core/error.hpp"
#include "hypershape/core/vec_array.hpp"
#include "hypershape/mesh/plex.hpp"

namespace hypershape::physics {

namespace {

PetscErrorCode zero_value(PetscInt, PetscReal, const PetscReal[], PetscInt nc, PetscScalar u[],
                          void*) {
  for (PetscInt c = 0; c < nc; ++c) u[c] = 0.0;
  return 0;
}

/// Vertex coordinates of `v` from the local coordinate vector.
std::array<double, 3> vertex_coords(PetscSection cs, const PetscScalar* xa, PetscInt v, int dim) {
  PetscInt off;
  HS_PETSC(PetscSectionGetOffset(cs, v, &off));
  std::array<double, 3> x{0, 0, 0};
  for (int k = 0; k < dim; ++k) x[k] = PetscRealPart(xa[off + k]);
  return x;
}

/// Closure points of `p` of depth `depth`, in closure order.
std::vector<PetscInt> closure_of_depth(DM dm, PetscInt p, PetscInt d0, PetscInt d1) {
  PetscInt n, *cl = nullptr;
  HS_PETSC(DMPlexGetTransitiveClosure(dm, p, PETSC_TRUE, &n, &cl));
  std::vector<PetscInt> out;
  for (PetscInt i = 0; i < n; ++i)
    if (cl[2 * i] >= d0 && cl[2 * i] < d1) out.push_back(cl[2 * i]);
  HS_PETSC(DMPlexRestoreTransitiveClosure(dm, p, PETSC_TRUE, &n, &cl));
  return out;
}

/// The unit normal of boundary facet `fv` pointing out of its (only) cell, in the reference
/// configuration: the geometric normal, flipped if it points towards the cell's centroid.
std::array<double, 3> outward_normal(DM dm, PetscSection cs, const PetscScalar* xa, const FacetView& fv,
                                     PetscInt v0, PetscInt v1, int dim) {
  const auto &a = fv.x[0], &b = fv.x[1];
  std::array<double, 3> n{b[1] - a[1], a[0] - b[0], 0.0};
  if (dim == 3) {
    const auto& c = fv.x[2];
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    n = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
  }
  const double norm = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  const PetscInt* support;
  HS_PETSC(DMPlexGetSupport(dm, fv.point, &support));
  const auto verts = closure_of_depth(dm, support[0], v0, v1);
  double towards_cell = 0;
  for (PetscInt v : verts) {
    const auto x = vertex_coords(cs, xa, v, dim);
    for (int k = 0; k < dim; ++k) towards_cell += (x[k] - a[k]) * n[k];
  }
  const double s = (towards_cell > 0 ? -1.0 : 1.0) / norm;
  for (double& c : n) c *= s;
  return n;
}

}  // namespace

std::array<double, 3> Space::node_coords(DM dm, PetscSection cs, const PetscScalar* xa, PetscInt p,
                                         int dim) {
  PetscInt depth;
  HS_PETSC(DMPlexGetPointDepth(dm, p, &depth));
  if (depth == 0) return vertex_coords(cs, xa, p, dim);
  const PetscInt* cone;
  HS_PETSC(DMPlexGetCone(dm, p, &cone));
  auto a = vertex_coords(cs, xa, cone[0], dim), b = vertex_coords(cs, xa, cone[1], dim);
  for (int k = 0; k < 3; ++k) a[k] = 0.5 * (a[k] + b[k]);
  return a;
}


namespace detail {

/// The canonical (rank-independent) node ids: the serial plex's vertices in order, then (P2)
/// its edges in order. Known on every rank (strata broadcast from rank 0).
struct CanonicalIds {
  PetscInt strata[4] = {0, 0, 0, 0};  // serial vStart, vEnd, eStart, eEnd
  std::int64_t n_vertices() const { return strata[1] - strata[0]; }
  std::int64_t operator()(PetscInt serial_point) const {
    if (serial_point >= strata[0] && serial_point < strata[1]) return serial_point - strata[0];
    return n_vertices() + (serial_point - strata[2]);
  }
};

CanonicalIds canonical_ids(DM serial, MPI_Comm comm) {
  CanonicalIds ids;
  if (core::rank(comm) == 0) {
    HS_PETSC(DMPlexGetDepthStratum(serial, 0, &ids.strata[0], &ids.strata[1]));
    HS_PETSC(DMPlexGetDepthStratum(serial, 1, &ids.strata[2], &ids.strata[3]));
  }
  MPI_Bcast(ids.strata, 4, MPIU_INT, 0, comm);
  return ids;
}

}  // namespace detail

namespace {


/// For each local point of `dm`, the serial plex's point it came from (through `migration`,
/// the SF of DMPlexDistribute; the identity without one).
std::vector<PetscInt> serial_points(DM dm, DM serial, PetscSF migration) {
  PetscInt p_start, p_end;
  HS_PETSC(DMPlexGetChart(dm, &p_start, &p_end));
  std::vector<PetscInt> original(std::size_t(p_end - p_start));
  if (!migration) {
    for (PetscInt p = p_start; p < p_end; ++p) original[p - p_start] = p;
    return original;
  }
  PetscInt s0 = 0, s1 = 0;
  HS_PETSC(DMPlexGetChart(serial, &s0, &s1));
  std::vector<PetscInt> identity(std::size_t(s1 - s0));
  for (PetscInt p = s0; p < s1; ++p) identity[p - s0] = p;
  HS_PETSC(PetscSFBcastBegin(migration, MPIU_INT, identity.data(), original.data(), MPI_REPLACE));
  HS_PETSC(PetscSFBcastEnd(migration, MPIU_INT, identity.data(), original.data(), MPI_REPLACE));
  return original;
}

/// 1 for the points of `dm` that are ghosts (leaves of the point SF), else 0.
std::vector<char> ghost_points(DM dm) {
  PetscInt p_start, p_end, n_roots, n_leaves;
  HS_PETSC(DMPlexGetChart(dm, &p_start, &p_end));
  PetscSF point_sf;
  HS_PETSC(DMGetPointSF(dm, &point_sf));
  const PetscInt* leaves;
  HS_PETSC(PetscSFGetGraph(point_sf, &n_roots, &n_leaves, &leaves, nullptr));
  std::vector<char> ghost(std::size_t(p_end - p_start), 0);
  for (PetscInt i = 0; i < n_leaves && n_leaves > 0; ++i) ghost[(leaves ? leaves[i] : i) - p_start] = 1;
  return ghost;
}

/// The labels of the essential conditions (a facet carrying one is not a Neumann facet).
std::vector<DMLabel> essential_labels(DM dm, const std::vector<EssentialBC>& bcs) {
  std::vector<DMLabel> ess;
  for (const auto& bc : bcs) {
    DMLabel l;
    HS_PETSC(DMGetLabel(dm, bc.label.c_str(), &l));
    ess.push_back(l);
  }
  return ess;
}

bool carries_any(const std::vector<DMLabel>& labels, PetscInt point) {
  bool any = false;
  for (DMLabel l : labels) {
    PetscInt val;
    HS_PETSC(DMLabelGetValue(l, point, &val));
    any = any || val == 1;
  }
  return any;
}

/// Facet `f` as the surface integrators see it: vertices, outward normal, and each dof-carrying
/// closure point's local offset and the facet vertices it lies between.
FacetView facet_view(DM dm, PetscSection ls, PetscSection cs, const PetscScalar* xa, PetscInt f,
                     PetscInt v0, PetscInt v1, int dim) {
  FacetView fv{};
  fv.point = f;
  const auto verts = closure_of_depth(dm, f, v0, v1);
  fv.n_vertices = int(verts.size());
  for (int a = 0; a < fv.n_vertices; ++a) fv.x[a] = vertex_coords(cs, xa, verts[a], dim);
  fv.normal = outward_normal(dm, cs, xa, fv, v0, v1, dim);
  auto index_of = [&](PetscInt v) { return int(std::find(verts.begin(), verts.end(), v) - verts.begin()); };
  PetscInt n, *cl = nullptr;
  HS_PETSC(DMPlexGetTransitiveClosure(dm, f, PETSC_TRUE, &n, &cl));
  fv.n_nodes = 0;
  for (PetscInt j = 0; j < n; ++j) {
    const PetscInt p = cl[2 * j];
    PetscInt dof, off;
    HS_PETSC(PetscSectionGetDof(ls, p, &dof));
    if (dof == 0) continue;
    HS_PETSC(PetscSectionGetOffset(ls, p, &off));
    std::array<int, 2> ends{};
    if (p >= v0 && p < v1) {
      ends = {index_of(p), index_of(p)};
    } else {
      const PetscInt* cone;
      HS_PETSC(DMPlexGetCone(dm, p, &cone));
      ends = {index_of(cone[0]), index_of(cone[1])};
    }
    fv.offset[fv.n_nodes] = off;
    fv.ends[fv.n_nodes] = ends;
    ++fv.n_nodes;
  }
  HS_PETSC(DMPlexRestoreTransitiveClosure(dm, f, PETSC_TRUE, &n, &cl));
  return fv;
}

}  // namespace

Space::Space(core::DMH dm, DM serial, PetscSF migration, const SpaceOptions& opt,
             const std::vector<EssentialBC>& bcs)
    : dm_(std::move(dm)), degree_(opt.degree) {
  if (degree_ != 1 && degree_ != 2) throw std::invalid_argument("degree must be 1 or 2");
  PetscInt d;
  HS_PETSC(DMGetDimension(dm_, &d));
  dim_ = int(d);
  n_nodes_ = degree_ == 1 ? dim_ + 1 : (dim_ + 1) * (dim_ + 2) / 2;
  core::QuadH q, fq;
  create_fe(opt, bcs, q, fq);
  tabulate_cell_rule(q);
  tabulate_facet_rule(fq);
  build_cells();
  Vec coords;
  PetscSection cs;
  HS_PETSC(DMGetCoordinatesLocal(dm_, &coords));
  HS_PETSC(DMGetCoordinateSection(dm_, &cs));
  const core::VecArray<const PetscScalar> xa(coords);
  collect_neumann_facets(bcs, cs, xa.data());
  number_nodes(serial, migration, cs, xa.data());
}

void Space::create_fe(const SpaceOptions& opt, const std::vector<EssentialBC>& bcs, core::QuadH& q,
                      core::QuadH& fq) {
  // Finite element with minimal symmetric rules (PETSc's default rules are 3-8x larger).
  const int qdeg = opt.quadrature_degree > 0 ? opt.quadrature_degree : 2 * degree_ - 1;
  const int fqdeg = opt.facet_quadrature_degree > 0 ? opt.facet_quadrature_degree : 2 * degree_ + 2;
  HS_PETSC(PetscFECreateLagrange(comm(), dim_, dim_, PETSC_TRUE, degree_, PETSC_DETERMINE, fe_.out()));
  HS_PETSC(PetscDTSimplexQuadrature(dim_, qdeg, PETSCDTSIMPLEXQUAD_MINSYM, q.out()));
  HS_PETSC(PetscDTSimplexQuadrature(dim_ - 1, fqdeg, PETSCDTSIMPLEXQUAD_MINSYM, fq.out()));
  HS_PETSC(PetscFESetQuadrature(fe_, q));
  HS_PETSC(PetscFESetFaceQuadrature(fe_, fq));
  HS_PETSC(PetscObjectSetName((PetscObject)fe_.get(), "displacement"));
  HS_PETSC(DMSetField(dm_, 0, nullptr, (PetscObject)fe_.get()));
  HS_PETSC(DMCreateDS(dm_));
  for (const auto& bc : bcs) {
    DMLabel label;
    HS_PETSC(DMGetLabel(dm_, bc.label.c_str(), &label));
    if (!label) throw std::logic_error("essential label " + bc.label + " is missing");
    const PetscInt one = 1;
    HS_PETSC(DMAddBoundary(dm_, DM_BC_ESSENTIAL, bc.label.c_str(), label, 1, &one, 0,
                           PetscInt(bc.components.size()), bc.components.data(),
                           (void (*)(void))zero_value, nullptr, nullptr, nullptr));
  }
}

void Space::tabulate_cell_rule(PetscQuadrature q) {
  // Reference basis at the quadrature points (closure order = PETSc's dof order).
  PetscInt qd, qnc, np;
  const PetscReal *pts, *wts;
  HS_PETSC(PetscQuadratureGetData(q, &qd, &qnc, &np, &pts, &wts));
  n_qp_ = int(np);
  qw_.assign(wts, wts + np);
  qxi_.assign(pts, pts + np * dim_);
  PetscTabulation T;
  HS_PETSC(PetscFECreateTabulation(fe_, 1, np, pts, 1, &T));
  const PetscInt nb = T->Nb, nc = T->Nc;
  if (nb != n_nodes_ * dim_ || nc != dim_) throw std::logic_error("unexpected tabulation size");
  N_.resize(std::size_t(np) * n_nodes_);
  dN_.resize(std::size_t(np) * n_nodes_ * dim_);
  for (int iq = 0; iq < n_qp_; ++iq)
    for (int a = 0; a < n_nodes_; ++a) {
      const PetscInt b = a * nc;  // component-0 function of node a, component 0
      N_[iq * n_nodes_ + a] = T->T[0][(iq * nb + b) * nc + 0];
      for (int k = 0; k < dim_; ++k)
        dN_[(std::size_t(iq) * n_nodes_ + a) * dim_ + k] = T->T[1][((iq * nb + b) * nc + 0) * dim_ + k];
    }
  HS_PETSC(PetscTabulationDestroy(&T));
}

void Space::tabulate_facet_rule(PetscQuadrature fq) {
  PetscInt qd, qnc, np;
  const PetscReal *pts, *wts;
  HS_PETSC(PetscQuadratureGetData(fq, &qd, &qnc, &np, &pts, &wts));
  double wsum = 0;
  for (PetscInt i = 0; i < np; ++i) wsum += wts[i];
  for (PetscInt i = 0; i < np; ++i) {
    fqw_.push_back(wts[i] / wsum);
    double l0 = 1.0;
    std::array<double, 3> bary{};
    for (int k = 0; k < dim_ - 1; ++k) {
      bary[k + 1] = 0.5 * (pts[i * (dim_ - 1) + k] + 1.0);
      l0 -= bary[k + 1];
    }
    bary[0] = l0;
    for (int k = 0; k < dim_; ++k) fbary_.push_back(bary[k]);
  }
}

void Space::build_cells() {
  // Per-cell geometry and dof indices.
  PetscSection ls, gs;
  HS_PETSC(DMGetLocalSection(dm_, &ls));
  HS_PETSC(DMGetGlobalSection(dm_, &gs));
  HS_PETSC(DMPlexGetHeightStratum(dm_, 0, &c0_, &c1_));
  all_cells_.resize(std::size_t(c1_ - c0_));
  std::iota(all_cells_.begin(), all_cells_.end(), c0_);
  const PetscInt nloc = c1_ - c0_;
  invJ_.resize(std::size_t(nloc) * dim_ * dim_);
  detJ_.resize(nloc);
  v0_.resize(std::size_t(nloc) * dim_);
  ldofs_.resize(std::size_t(nloc) * n_cell_dofs());
  gdofs_.resize(std::size_t(nloc) * n_cell_dofs());
  for (PetscInt c = c0_; c < c1_; ++c) {
    double v0[3], J[9], iJ[9], detJ;
    HS_PETSC(DMPlexComputeCellGeometryAffineFEM(dm_, c, v0, J, iJ, &detJ));
    if (!(detJ > 0)) throw std::logic_error("cell with det J <= 0 reached the space");
    std::copy(iJ, iJ + dim_ * dim_, &invJ_[std::size_t(c - c0_) * dim_ * dim_]);
    std::copy(v0, v0 + dim_, &v0_[std::size_t(c - c0_) * dim_]);
    detJ_[c - c0_] = detJ;
    cell_dofs(c, ls, gs);
  }
  long long nc_loc = nloc;
  MPI_Allreduce(MPI_IN_PLACE, &nc_loc, 1, MPI_LONG_LONG, MPI_SUM, comm());
  n_cells_global_ = nc_loc;
  Vec g;
  PetscInt n;
  HS_PETSC(DMGetGlobalVector(dm_, &g));
  HS_PETSC(VecGetSize(g, &n));
  HS_PETSC(DMRestoreGlobalVector(dm_, &g));
  n_dofs_global_ = n;
}

void Space::cell_dofs(PetscInt c, PetscSection ls, PetscSection gs) {
  PetscInt n, *cl = nullptr, k = 0;
  HS_PETSC(DMPlexGetTransitiveClosure(dm_, c, PETSC_TRUE, &n, &cl));
  PetscInt* ld = &ldofs_[std::size_t(c - c0_) * n_cell_dofs()];
  for (PetscInt i = 0; i < n; ++i) {
    PetscInt dof, off;
    HS_PETSC(PetscSectionGetDof(ls, cl[2 * i], &dof));
    HS_PETSC(PetscSectionGetOffset(ls, cl[2 * i], &off));
    for (PetscInt j = 0; j < dof; ++j) {
      if (k >= n_cell_dofs()) throw std::logic_error("closure has too many dofs");
      ld[k++] = off + j;
    }
  }
  HS_PETSC(DMPlexRestoreTransitiveClosure(dm_, c, PETSC_TRUE, &n, &cl));
  if (k != n_cell_dofs()) throw std::logic_error("closure has too few dofs");
  PetscInt ni, *idx = nullptr;
  HS_PETSC(DMPlexGetClosureIndices(dm_, ls, gs, c, PETSC_TRUE, &ni, &idx, nullptr, nullptr));
  if (ni != n_cell_dofs()) throw std::logic_error("closure index count mismatch");
  std::copy(idx, idx + ni, &gdofs_[std::size_t(c - c0_) * n_cell_dofs()]);
  HS_PETSC(DMPlexRestoreClosureIndices(dm_, ls, gs, c, PETSC_TRUE, &ni, &idx, nullptr, nullptr));
}

void Space::collect_neumann_facets(const std::vector<EssentialBC>& bcs, PetscSection cs, const PetscScalar* xa) {
  // Neumann facets: boundary facets carrying none of the essential labels.
  const std::vector<DMLabel> ess = essential_labels(dm_, bcs);
  PetscSection ls;
  HS_PETSC(DMGetLocalSection(dm_, &ls));
  PetscInt v0, v1;
  HS_PETSC(DMPlexGetDepthStratum(dm_, 0, &v0, &v1));
  IS facets = nullptr;
  HS_PETSC(DMGetStratumIS(dm_, mesh::boundary_label, 1, &facets));
  if (!facets) return;
  PetscInt nf = 0;
  const PetscInt* fp = nullptr;
  HS_PETSC(ISGetLocalSize(facets, &nf));
  HS_PETSC(ISGetIndices(facets, &fp));
  for (PetscInt i = 0; i < nf; ++i)
    if (!carries_any(ess, fp[i])) neumann_facets_.push_back(facet_view(dm_, ls, cs, xa, fp[i], v0, v1, dim_));
  HS_PETSC(ISRestoreIndices(facets, &fp));
  HS_PETSC(ISDestroy(&facets));
}

void Space::number_nodes(DM serial, PetscSF migration, PetscSection cs, const PetscScalar* xa) {
  // Canonical numbering: vertices of the serial plex in order, then (P2) its edges in order.
  const detail::CanonicalIds canonical = detail::canonical_ids(serial, comm());
  n_vertices_global_ = canonical.n_vertices();
  n_nodes_global_ = n_vertices_global_ + (degree_ == 2 ? canonical.strata[3] - canonical.strata[2] : 0);
  const std::vector<PetscInt> original = serial_points(dm_, serial, migration);
  const std::vector<char> ghost = ghost_points(dm_);
  PetscSection ls;
  HS_PETSC(DMGetLocalSection(dm_, &ls));
  PetscInt p_start, p_end;
  HS_PETSC(DMPlexGetChart(dm_, &p_start, &p_end));
  for (PetscInt p = p_start; p < p_end; ++p) {
    PetscInt dof, off;
    HS_PETSC(PetscSectionGetDof(ls, p, &dof));
    if (dof == 0 || ghost[p - p_start]) continue;
    HS_PETSC(PetscSectionGetOffset(ls, p, &off));
    owned_nodes_.push_back({off, canonical(original[p - p_start]), node_coords(dm_, cs, xa, p, dim_)});
  }
  if (core::rank(comm()) == 0) build_output_mesh(serial, canonical);
}

void Space::build_output_mesh(DM serial, const detail::CanonicalIds& canonical) {
  // Canonical connectivity and coordinates for output, from the serial plex (rank 0).
  const PetscInt* strata = canonical.strata;
  Vec sc;
  PetscSection scs;
  HS_PETSC(DMGetCoordinatesLocal(serial, &sc));
  HS_PETSC(DMGetCoordinateSection(serial, &scs));
  const core::VecArray<const PetscScalar> sxa(sc);
  canonical_coords_.resize(std::size_t(n_nodes_global_) * dim_);
  auto store = [&](PetscInt p) {
    const auto x = node_coords(serial, scs, sxa.data(), p, dim_);
    std::copy(x.begin(), x.begin() + dim_, &canonical_coords_[std::size_t(canonical(p)) * dim_]);
  };
  for (PetscInt p = strata[0]; p < strata[1]; ++p) store(p);
  if (degree_ == 2)
    for (PetscInt p = strata[2]; p < strata[3]; ++p) store(p);
  PetscInt sc0, sc1;
  HS_PETSC(DMPlexGetHeightStratum(serial, 0, &sc0, &sc1));
  for (PetscInt c = sc0; c < sc1; ++c) {
    auto v = closure_of_depth(serial, c, strata[0], strata[1]);
    if (dim_ == 3) std::swap(v[1], v[2]);  // PETSc's left-handed tetrahedra -> VTK's
    for (auto p : v) canonical_cells_.push_back(canonical(p));
    if (degree_ != 2) continue;
    for (const auto& [a, b] : mesh::edges(dim_)) {
      const PetscInt pair[2] = {v[a], v[b]};
      PetscInt nj;
      const PetscInt* join;
      HS_PETSC(DMPlexGetJoin(serial, 2, pair, &nj, &join));
      canonical_cells_.push_back(canonical(join[0]));
      HS_PETSC(DMPlexRestoreJoin(serial, 2, pair, &nj, &join));
    }
  }
}

void Space::map_point(PetscInt c, int q, double* x) const {
  // x = v0 + J (xi + 1), J = inverse of invJ.
  const double* iJ = inv_jacobian(c);
  const double* v0 = &v0_[std::size_t(c - c0_) * dim_];
  const double* xi = &qxi_[std::size_t(q) * dim_];
  if (dim_ == 2) {
    Eigen::Map<const Eigen::Matrix<double, 2, 2, Eigen::RowMajor>> m(iJ);
    Eigen::Vector2d r = m.inverse() * Eigen::Vector2d(xi[0] + 1, xi[1] + 1);
    x[0] = v0[0] + r[0];
    x[1] = v0[1] + r[1];
  } else {
    Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> m(iJ);
    Eigen::Vector3d r = m.inverse() * Eigen::Vector3d(xi[0] + 1, xi[1] + 1, xi[2] + 1);
    for (int k = 0; k < 3; ++k) x[k] = v0[k] + r[k];
  }
}

double Space::facet_basis(const std::array<int, 2>& ends, const double* bary) const {
  const double la = bary[ends[0]];
  if (ends[0] == ends[1]) return degree_ == 1 ? la : la * (2.0 * la - 1.0);
  return 4.0 * la * bary[ends[1]];
}

double Space::facet_measure(const FacetView& f, int dim) {
  const auto &a = f.x[0], &b = f.x[1];
  if (dim == 2) return std::hypot(b[0] - a[0], b[1] - a[1]);
  const auto& c = f.x[2];
  const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  const double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
  return 0.5 * std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
}

double Space::min_det_jacobian() const {
  double m = detJ_.empty() ? 1e300 : *std::min_element(detJ_.begin(), detJ_.end());
  MPI_Allreduce(MPI_IN_PLACE, &m, 1, MPI_DOUBLE, MPI_MIN, comm());
  return m;
}

const std::vector<PetscInt>& Space::csr_offsets(Mat J) const {
  PetscInt64 id;
  PetscObjectState nz;
  HS_PETSC(PetscObjectGetId((PetscObject)J, &id));
  HS_PETSC(MatGetNonzeroState(J, &nz));
  const std::pair key{id, nz};
  if (std::find(csr_matrices_.begin(), csr_matrices_.end(), key) != csr_matrices_.end()) return csr_offsets_;
  PetscInt n;
  const PetscInt *ia, *ja;
  PetscBool done;
  HS_PETSC(MatGetRowIJ(J, 0, PETSC_FALSE, PETSC_FALSE, &n, &ia, &ja, &done));
  if (!done) {
    static const std::vector<PetscInt> none;
    return none;
  }
  const bool known = build_csr_offsets(ia, ja, n);
  HS_PETSC(MatRestoreRowIJ(J, 0, PETSC_FALSE, PETSC_FALSE, &n, &ia, &ja, &done));
  if (known) {
    if (csr_matrices_.size() >= 16) csr_matrices_.erase(csr_matrices_.begin());  // (a short list: a few live matrices)
    csr_matrices_.push_back(key);
  }
  return csr_offsets_;
}

bool Space::build_csr_offsets(const PetscInt* ia, const PetscInt* ja, PetscInt n) const {
  const PetscInt nnz = ia[n];
  const bool same = csr_ia_.size() == std::size_t(n + 1) && csr_ja_.size() == std::size_t(nnz) &&
                    std::equal(ia, ia + n + 1, csr_ia_.begin()) && std::equal(ja, ja + nnz, csr_ja_.begin());
  if (same) return true;
  csr_matrices_.clear();  // their pattern is not the one computed now
  csr_ia_.assign(ia, ia + n + 1);
  csr_ja_.assign(ja, ja + nnz);
  const int nd = n_cell_dofs();
  csr_offsets_.assign(std::size_t(c1_ - c0_) * std::size_t(nd * nd), -1);
  for (PetscInt c = c0_; c < c1_; ++c) {
    const PetscInt* g = global_dofs(c);
    PetscInt* off = &csr_offsets_[std::size_t(c - c0_) * std::size_t(nd * nd)];
    for (int a = 0; a < nd; ++a) {
      if (g[a] < 0) continue;
      const PetscInt* row = ja + ia[g[a]];
      const PetscInt* end = ja + ia[g[a] + 1];
      for (int b = 0; b < nd; ++b) {
        if (g[b] < 0) continue;
        const PetscInt* it = std::lower_bound(row, end, g[b]);
        if (it == end || *it != g[b]) {  // not in the pattern: the direct path cannot be used
          csr_ia_.clear();
          csr_offsets_.clear();
          return false;
        }
        off[a * nd + b] = PetscInt(it - ja);
      }
    }
  }
  return true;
}

namespace {

/// CSR pattern of the local rows [0, n) (serial: global = local indices): for each row, the
/// sorted free dofs of the cells that carry it. Cells listed per row first, then one marker pass.
void cell_pattern(PetscInt n, PetscInt n_cells, int nd, const PetscInt* gdofs, std::vector<PetscInt>& ia,
                  std::vector<PetscInt>& ja) {
  std::vector<PetscInt> start(std::size_t(n) + 1, 0);
  const auto dof = [&](PetscInt c, int i) { return gdofs[std::size_t(c) * std::size_t(nd) + std::size_t(i)]; };
  for (PetscInt c = 0; c < n_cells; ++c)
    for (int i = 0; i < nd; ++i) {
      if (dof(c, i) >= n) throw std::logic_error("cell_pattern: a cell's dof is not a local row");
      if (dof(c, i) >= 0) ++start[std::size_t(dof(c, i)) + 1];
    }
  for (std::size_t r = 0; r < std::size_t(n); ++r) start[r + 1] += start[r];
  std::vector<PetscInt> cells(std::size_t(start.back())), fill(start.begin(), start.end() - 1);
  for (PetscInt c = 0; c < n_cells; ++c)
    for (int i = 0; i < nd; ++i)
      if (dof(c, i) >= 0) cells[std::size_t(fill[std::size_t(dof(c, i))]++)] = c;
  std::vector<PetscInt> mark(std::size_t(n), -1);
  ia.assign(1, 0);
  ja.clear();
  for (PetscInt r = 0; r < n; ++r) {
    const auto row_begin = ja.size();
    for (auto k = start[std::size_t(r)]; k < start[std::size_t(r) + 1]; ++k)
      for (int j = 0; j < nd; ++j) {
        const PetscInt col = dof(cells[std::size_t(k)], j);
        if (col >= 0 && mark[std::size_t(col)] != r) mark[std::size_t(col)] = r, ja.push_back(col);
      }
    std::sort(ja.begin() + std::ptrdiff_t(row_begin), ja.end());
    ia.push_back(PetscInt(ja.size()));
  }
}

}  // namespace

core::MatH Space::create_matrix() const {
  core::MatH J;
  DM dm = dm_.get();
  if (core::size(comm()) > 1) {
    HS_PETSC(DMCreateMatrix(dm, J.out()));
    return J;
  }
  // DMCreateMatrix without its preallocation: the type, sizes, block size, local-to-global map
  // and DM as it sets them; then the pattern, from the cells.
  HS_PETSC(DMSetMatrixPreallocateSkip(dm, PETSC_TRUE));
  const PetscErrorCode err = DMCreateMatrix(dm, J.out());
  HS_PETSC(DMSetMatrixPreallocateSkip(dm, PETSC_FALSE));
  HS_PETSC(err);
  PetscBool seqaij = PETSC_FALSE;
  HS_PETSC(PetscObjectTypeCompare((PetscObject)J.get(), MATSEQAIJ, &seqaij));
  if (!seqaij) {  // another type (-dm_mat_type): DMCreateMatrix's own preallocation
    core::MatH K;
    HS_PETSC(DMCreateMatrix(dm, K.out()));
    return K;
  }
  PetscInt n;
  HS_PETSC(MatGetLocalSize(J, &n, nullptr));
  std::vector<PetscInt> ia, ja;
  cell_pattern(n, c1_ - c0_, n_cell_dofs(), gdofs_.data(), ia, ja);
  HS_PETSC(MatSeqAIJSetPreallocationCSR(J, ia.data(), ja.data(), nullptr));
  return J;
}

CellMatrixAdder::CellMatrixAdder(const Space& space, Mat J) : space_(space), J_(J), n_(space.n_cell_dofs()) {
  PetscBool seqaij = PETSC_FALSE, assembled = PETSC_FALSE;
  HS_PETSC(PetscObjectTypeCompare((PetscObject)J, MATSEQAIJ, &seqaij));
  if (seqaij) HS_PETSC(MatAssembled(J, &assembled));
  if (!seqaij || !assembled) return;  // the first assembly fixes the pattern: MatSetValues
  const auto& off = space.csr_offsets(J);
  if (off.empty() && space.c1_ > space.c0_) return;
  offsets_ = off.data();
  HS_PETSC(MatSeqAIJGetArray(J, &values_));
}

void CellMatrixAdder::zero(PetscInt c) const {
  const std::size_t nn = std::size_t(n_) * std::size_t(n_);
  const PetscInt* off = offsets_ + std::size_t(c - space_.c0_) * nn;
  for (std::size_t k = 0; k < nn; ++k)
    if (off[k] >= 0) values_[off[k]] = 0.0;
}

CellMatrixAdder::~CellMatrixAdder() {
  if (values_) MatSeqAIJRestoreArray(J_, &values_);  // no throw from a destructor
}

void CellMatrixAdder::add(PetscInt c, const double* Ke) const {
  if (!values_) {
    const PetscInt* g = space_.global_dofs(c);
    HS_PETSC(MatSetValues(J_, n_, g, n_, g, Ke, ADD_VALUES));
    return;
  }
  const std::size_t nn = std::size_t(n_) * std::size_t(n_);
  const PetscInt* off = offsets_ + std::size_t(c - space_.c0_) * nn;
  // In pairs: a node's two dofs (2D) are neighbours in a CSR row, added as one two-lane vector.
  using V2 = double __attribute__((vector_size(16)));
  std::size_t k = 0;
  for (; k + 1 < nn; k += 2) {
    const PetscInt o = off[k];
    if (o >= 0 && off[k + 1] == o + 1) {
      V2 v, e;
      std::memcpy(&v, values_ + o, sizeof v);
      std::memcpy(&e, Ke + k, sizeof e);
      v += e;
      std::memcpy(values_ + o, &v, sizeof v);
      continue;
    }
    if (o >= 0) values_[o] += Ke[k];
    if (off[k + 1] >= 0) values_[off[k + 1]] += Ke[k + 1];
  }
  if (k < nn && off[k] >= 0) values_[off[k]] += Ke[k];
}

}  // namespace hypershape::physics
