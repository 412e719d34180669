#include "hypershape/physics/problem.hpp"

#include <petscdmplex.h>
#include <petscsnes.h>

#include <algorithm>
#include <cassert>
#include <cmath>

#include "hypershape/core/error.hpp"
#include "hypershape/core/vec_array.hpp"
#include "hypershape/mesh/plex.hpp"
#include "hypershape/physics/hyperelastic.hpp"

namespace hypershape::physics {

namespace {

using core::LocalArray;

/// m += x × f (3-vectors; 2D vectors have a zero third component).
void add_moment(const double* x, const double* f, std::array<double, 3>& m) {
  m[0] += x[1] * f[2] - x[2] * f[1];
  m[1] += x[2] * f[0] - x[0] * f[2];
  m[2] += x[0] * f[1] - x[1] * f[0];
}

bool all_ranks(MPI_Comm comm, bool ok) {
  int v = ok ? 1 : 0;
  MPI_Allreduce(MPI_IN_PLACE, &v, 1, MPI_INT, MPI_MIN, comm);
  return v == 1;
}

/// PETSc's pointwise assembly reads closures through the closure index (3D P1 residual 4.8x
/// faster with it); only it does, so it is built at its first call, not with every space.
void ensure_closure_index(DM dm) {
  PetscSection s, cl_section = nullptr;
  IS cl_points = nullptr;
  HS_PETSC(DMGetLocalSection(dm, &s));
  HS_PETSC(PetscSectionGetClosureIndex(s, (PetscObject)dm, &cl_section, &cl_points));
  if (!cl_section) HS_PETSC(DMPlexCreateClosureIndex(dm, nullptr));
}

}  // namespace

Problem::Problem(MPI_Comm comm, const mesh::MeshData& mesh, std::vector<EffectPtr> effects,
                 const SpaceOptions& opt)
    : effects_(std::move(effects)) {
  core::DMH serial = mesh::create_plex(comm, mesh);
  std::vector<EssentialBC> bcs;
  for (auto& e : effects_) {
    e->mark(serial);
    for (auto& bc : e->essential_bcs()) bcs.push_back(bc);
  }
  core::SFH migration;
  core::DMH dist = mesh::distribute(serial, migration);
  const bool distributed = bool(dist);
  // Space takes the plex it works on; keep the serial one alive for the canonical numbering.
  if (distributed) {
    space_ = std::make_unique<Space>(std::move(dist), serial.get(), migration.get(), opt, bcs);
  } else {
    DM clone;
    HS_PETSC(PetscObjectReference((PetscObject)serial.get()));
    clone = serial.get();
    space_ = std::make_unique<Space>(core::DMH(clone), serial.get(), nullptr, opt, bcs);
  }
  for (auto& e : effects_) e->setup(*space_);
  for (auto& e : effects_) {
    has_follower_ = has_follower_ || e->follower();
    has_scaled_follower_ = has_scaled_follower_ || (e->follower() && e->scaled());
  }
  HS_PETSC(DMCreateGlobalVector(dm(), load_.out()));
  assemble_load();
}

void Problem::assemble_loads(bool scaled, Vec f) const {
  HS_PETSC(VecZeroEntries(f));
  LocalArray fl(dm(), true);
  for (auto& e : effects_)
    if (e->has_load() && e->active() && e->scaled() == scaled && !e->follower()) e->add_load(*space_, fl.array());
  fl.release();
  HS_PETSC(DMLocalToGlobal(dm(), fl.vec(), ADD_VALUES, f));
}

void Problem::assemble_load() {
  assemble_loads(true, load_);
  if (has_scaled_follower_) {  // the nominal load: f_ext + f_s(0)
    if (!nominal_) HS_PETSC(VecDuplicate(load_, nominal_.out()));
    LocalArray fl(dm(), true);
    for (auto& e : effects_)
      if (e->follower() && e->active() && e->scaled()) e->add_follower_load(*space_, nullptr, 1.0, fl.array());
    fl.release();
    HS_PETSC(VecCopy(load_, nominal_));
    HS_PETSC(DMLocalToGlobal(dm(), fl.vec(), ADD_VALUES, nominal_));
  }
  HS_PETSC(VecNorm(load(), NORM_2, &load_norm_));
  // A fixed load is allocated and assembled only when some effect has one.
  const bool any_fixed = std::any_of(effects_.begin(), effects_.end(), [](const EffectPtr& e) {
    return e->has_load() && !e->scaled() && !e->follower();
  });
  if (!any_fixed) return;
  if (!fixed_load_) HS_PETSC(DMCreateGlobalVector(dm(), fixed_load_.out()));
  assemble_loads(false, fixed_load_);
}

bool Problem::has_fixed_load() const {
  return std::any_of(effects_.begin(), effects_.end(),
                     [](const EffectPtr& e) { return e->has_load() && !e->scaled() && e->active(); });
}

void Problem::reassemble_load() {
  for (auto& e : effects_)
    if (e->has_load()) e->setup(*space_);
  assemble_load();
}

void Problem::replace_load(std::size_t index, EffectPtr effect) {
  assert(index < effects_.size() && effects_[index]->has_load() && !effects_[index]->has_energy() &&
         effects_[index]->essential_bcs().empty() && effect->has_load());
  effects_[index] = std::move(effect);
}

void Problem::to_local(Vec u, Vec ul) const {
  // Every essential condition is homogeneous: zeroing the local vector before the scatter
  // sets the constrained entries. DMPlexInsertBoundaryValues gave the same bits but cost
  // 90-97% of a P1 residual (bench_solver, to_local column).
  HS_PETSC(VecZeroEntries(ul));
  HS_PETSC(DMGlobalToLocal(dm(), u, INSERT_VALUES, ul));
}

void Problem::add_follower_loads(const PetscScalar* u, double load_factor, PetscScalar* r) const {
  for (auto& e : effects_)
    if (e->follower() && e->active()) e->add_follower_load(*space_, u, -(e->scaled() ? load_factor : 1.0), r);
}

void Problem::add_follower_force(Vec u, double scaled_weight, double fixed_weight, Vec f) const {
  LocalArray ul(dm(), false), fl(dm(), true);
  to_local(u, ul.vec());
  for (auto& e : effects_)
    if (e->follower() && e->active())
      e->add_follower_load(*space_, ul.array(), e->scaled() ? scaled_weight : fixed_weight, fl.array());
  fl.release();
  HS_PETSC(DMLocalToGlobal(dm(), fl.vec(), ADD_VALUES, f));
}

Vec Problem::load_at(Vec u) const {
  if (!has_scaled_follower_) return load_.get();
  if (!load_at_) HS_PETSC(VecDuplicate(load_, load_at_.out()));
  HS_PETSC(VecCopy(load_, load_at_));
  add_follower_force(u, 1.0, 0.0, load_at_);
  return load_at_.get();
}

bool Problem::energy_along(Vec from, Vec to, double load_factor, double& value) const {
  const bool ok = energy(to, load_factor, value);
  if (!ok || !has_follower_) return ok;
  for (auto& v : along_)
    if (!v) HS_PETSC(VecDuplicate(load_, v.out()));
  Vec d = along_[0], mid = along_[1], f = along_[2];
  HS_PETSC(VecWAXPY(d, -1.0, from, to));
  HS_PETSC(VecWAXPY(mid, 0.5, d, from));
  HS_PETSC(VecZeroEntries(f));  // Simpson: (f(from) + 4 f(mid) + f(to)) / 6
  add_follower_force(from, load_factor / 6, 1.0 / 6, f);
  add_follower_force(mid, 4 * load_factor / 6, 4.0 / 6, f);
  add_follower_force(to, load_factor / 6, 1.0 / 6, f);
  PetscScalar work;
  HS_PETSC(VecDot(f, d, &work));
  value -= PetscRealPart(work);
  return true;
}

bool Problem::energy(Vec u, double load_factor, double& value, double* internal) const {
  LocalArray ul(dm(), false);
  to_local(u, ul.vec());
  double e = 0;
  bool ok = true;
  for (auto& eff : effects_)
    if (eff->has_energy()) ok = ok && eff->add_energy(*space_, ul.array(), e);
  ok = all_ranks(comm(), ok);
  MPI_Allreduce(MPI_IN_PLACE, &e, 1, MPI_DOUBLE, MPI_SUM, comm());
  if (internal) *internal = e;
  value = ok ? energy_from_internal(u, load_factor, e) : INFINITY;
  return ok;
}

double Problem::energy_from_internal(Vec u, double load_factor, double internal) const {
  PetscScalar work, fixed = 0;
  HS_PETSC(VecDot(load_, u, &work));
  if (fixed_load_) HS_PETSC(VecDot(fixed_load_, u, &fixed));
  return internal - load_factor * PetscRealPart(work) - PetscRealPart(fixed);
}

bool Problem::residual(Vec u, double load_factor, Vec r) const {
  LocalArray ul(dm(), false), rl(dm(), true);
  to_local(u, ul.vec());
  bool ok = true;
  for (auto& eff : effects_)
    if (eff->has_energy()) ok = ok && eff->add_residual(*space_, ul.array(), rl.array());
  if (has_follower_) add_follower_loads(ul.array(), load_factor, rl.array());
  ok = all_ranks(comm(), ok);
  finish_residual(rl, load_factor, r);
  return ok;
}

bool Problem::energy_residual(Vec u, double load_factor, double& value, Vec r, double* internal,
                              Vec internal_force) const {
  if (has_follower_) {  // energy_along's merit function, not this energy
    throw std::logic_error("Problem::energy_residual: a follower load has no energy");
  }
  LocalArray ul(dm(), false), rl(dm(), true);
  to_local(u, ul.vec());
  double e = 0;
  bool ok = true;
  for (auto& eff : effects_)
    if (eff->has_energy()) ok = ok && eff->add_energy_residual(*space_, ul.array(), e, rl.array());
  ok = all_ranks(comm(), ok);
  MPI_Allreduce(MPI_IN_PLACE, &e, 1, MPI_DOUBLE, MPI_SUM, comm());
  if (internal) *internal = e;
  value = ok ? energy_from_internal(u, load_factor, e) : INFINITY;
  if (ok) finish_residual(rl, load_factor, r, internal_force);
  return ok;
}

void Problem::residual_from_internal(Vec internal_force, double load_factor, Vec r) const {
  HS_PETSC(VecCopy(internal_force, r));
  subtract_loads(load_factor, r);
}

void Problem::finish_residual(LocalArray& rl, double load_factor, Vec r, Vec internal_force) const {
  rl.release();
  HS_PETSC(VecZeroEntries(r));
  HS_PETSC(DMLocalToGlobal(dm(), rl.vec(), ADD_VALUES, r));
  if (internal_force) HS_PETSC(VecCopy(r, internal_force));
  subtract_loads(load_factor, r);
}

void Problem::subtract_loads(double load_factor, Vec r) const {
  if (load_factor != 0.0) HS_PETSC(VecAXPY(r, -load_factor, load_));
  if (fixed_load_) HS_PETSC(VecAXPY(r, -1.0, fixed_load_));
}

void Problem::zero_tangent(Mat J) const {
  // Under a CellSubset (a local solve's patch) on one rank, only the entries its cells add to:
  // a patch's tangent is read at the dofs whose cells all lie in it, and zeroing all of J for
  // each of its steps was two thirds of the memset time of a Random2D P2 run (callgrind).
  if (space_->restricted()) {
    const CellMatrixAdder adder(*space_, J);
    if (adder.direct()) {
      for (const PetscInt c : space_->cells()) adder.zero(c);
      return;
    }
  }
  HS_PETSC(MatZeroEntries(J));
}

bool Problem::jacobian(Vec u, Mat J, double load_factor) const {
  LocalArray ul(dm(), false);
  to_local(u, ul.vec());
  zero_tangent(J);
  bool ok = true;
  for (auto& eff : effects_) {
    if (eff->has_energy()) ok = ok && eff->add_jacobian(*space_, ul.array(), J);
    if (eff->follower() && eff->active())
      eff->add_follower_jacobian(*space_, ul.array(), eff->scaled() ? load_factor : 1.0, J);
  }
  HS_PETSC(MatAssemblyBegin(J, MAT_FINAL_ASSEMBLY));
  HS_PETSC(MatAssemblyEnd(J, MAT_FINAL_ASSEMBLY));
  return all_ranks(comm(), ok);
}

void Problem::residual_pointwise(Vec u, Vec r) const {
  ensure_closure_index(dm());
  PetscDS ds;
  HS_PETSC(DMGetDS(dm(), &ds));
  for (auto& eff : effects_)
    if (eff->has_energy()) eff->set_pointwise(ds);
  LocalArray ul(dm(), false), rl(dm(), true);
  to_local(u, ul.vec());
  HS_PETSC(DMPlexSNESComputeResidualFEM(dm(), ul.vec(), rl.vec(), nullptr));
  HS_PETSC(VecZeroEntries(r));
  HS_PETSC(DMLocalToGlobal(dm(), rl.vec(), ADD_VALUES, r));
}

void Problem::jacobian_pointwise(Vec u, Mat J) const {
  ensure_closure_index(dm());
  PetscDS ds;
  HS_PETSC(DMGetDS(dm(), &ds));
  for (auto& eff : effects_)
    if (eff->has_energy()) eff->set_pointwise(ds);
  LocalArray ul(dm(), false);
  to_local(u, ul.vec());
  HS_PETSC(DMPlexSNESComputeJacobianFEM(dm(), ul.vec(), J, J, nullptr));
}

Resultants Problem::resultants(Vec u, double load_factor) const {
  const int dim = space_->dim();
  LocalArray ul(dm(), false), fi(dm(), true), fs(dm(), true), fe(dm(), true), ff(dm(), true);
  to_local(u, ul.vec());
  bool ok = true;
  for (auto& eff : effects_) {
    // An elastic support's force (a spring) does not sum to zero like the material's: it is an
    // external force on the body, kept apart so that the balance closes (spring_force).
    if (eff->has_energy())
      ok = ok && eff->add_residual(*space_, ul.array(), eff->is_material() ? fi.array() : fs.array());
    // A follower load acts with its force at the state.
    if (eff->has_load() && eff->active() && eff->follower())
      eff->add_follower_load(*space_, ul.array(), 1.0, eff->scaled() ? fe.array() : ff.array());
    else if (eff->has_load() && eff->active()) eff->add_load(*space_, eff->scaled() ? fe.array() : ff.array());
  }
  Resultants out;
  out.admissible = all_ranks(comm(), ok);
  // Nothing is scattered: every cell and every Neumann facet is on exactly one rank, so the sum
  // of all local entries (ghosts included) over the ranks counts each contribution once, and the
  // constrained entries, which the global layout drops, are still there.
  PetscSection ls, cs;
  Vec coords;
  HS_PETSC(DMGetLocalSection(dm(), &ls));
  HS_PETSC(DMGetCoordinateSection(dm(), &cs));
  HS_PETSC(DMGetCoordinatesLocal(dm(), &coords));
  const core::VecArray<const PetscScalar> xa(coords);
  const PetscScalar *a = ul.array(), *f_int = fi.array(), *f_spring = fs.array(), *f_ext = fe.array(),
                    *f_fix = ff.array();
  PetscInt p0, p1;
  HS_PETSC(PetscSectionGetChart(ls, &p0, &p1));
  for (PetscInt p = p0; p < p1; ++p) {
    PetscInt n_dof, off, n_con;
    HS_PETSC(PetscSectionGetDof(ls, p, &n_dof));
    if (n_dof == 0) continue;
    HS_PETSC(PetscSectionGetOffset(ls, p, &off));
    HS_PETSC(PetscSectionGetConstraintDof(ls, p, &n_con));
    const std::array<double, 3> x = Space::node_coords(dm(), cs, xa.data(), p, dim);
    double y[3] = {0, 0, 0}, load[3] = {0, 0, 0}, support[3] = {0, 0, 0}, spring[3] = {0, 0, 0};
    for (int i = 0; i < dim; ++i) {
      y[i] = x[i] + PetscRealPart(a[off + i]);
      load[i] = load_factor * PetscRealPart(f_ext[off + i]) + PetscRealPart(f_fix[off + i]);
      spring[i] = -PetscRealPart(f_spring[off + i]);  // the spring pulls back: -K u
      out.applied_force[i] += load[i];
      out.spring_force[i] += spring[i];
    }
    add_moment(y, load, out.applied_moment);
    add_moment(x.data(), load, out.applied_moment_reference);
    add_moment(y, spring, out.spring_moment);
    if (n_con == 0) continue;
    const PetscInt* con;
    HS_PETSC(PetscSectionGetConstraintIndices(ls, p, &con));
    for (PetscInt k = 0; k < n_con; ++k) {
      const PetscInt i = con[k];
      support[i] = PetscRealPart(f_int[off + i]) - spring[i] - load[i];
      out.reaction_force[i] += support[i];
    }
    add_moment(y, support, out.reaction_moment);
  }
  for (auto* v : {&out.reaction_force, &out.reaction_moment, &out.applied_force, &out.applied_moment,
                  &out.applied_moment_reference, &out.spring_force, &out.spring_moment})
    MPI_Allreduce(MPI_IN_PLACE, v->data(), 3, MPI_DOUBLE, MPI_SUM, comm());
  return out;
}

double Problem::max_displacement(Vec u) const {
  LocalArray ul(dm(), false);
  to_local(u, ul.vec());
  const PetscScalar* a = ul.array();
  double m = 0;
  for (const auto& n : space_->owned_nodes()) {
    double s = 0;
    for (int i = 0; i < space_->dim(); ++i) s += a[n.offset + i] * a[n.offset + i];
    m = std::max(m, s);
  }
  MPI_Allreduce(MPI_IN_PLACE, &m, 1, MPI_DOUBLE, MPI_MAX, comm());
  return std::sqrt(m);
}

double Problem::min_det_f(Vec u) const {
  LocalArray ul(dm(), false);
  to_local(u, ul.vec());
  const PetscScalar* a = ul.array();
  const Space& s = *space_;
  double m = INFINITY;
  detail::dispatch(s, [&]<int D, int NB>() {
    Eigen::Matrix<double, NB, D> ue, G;
    for (PetscInt c = s.cell_begin(); c < s.cell_end(); ++c) {
      detail::gather<D, NB>(s, c, a, ue);
      for (int q = 0; q < s.n_qp(); ++q) {
        detail::physical_gradients<D, NB>(s, c, q, G);
        m = std::min(m, detail::deformation_gradient<D, NB>(ue, G).determinant());
      }
    }
    return true;
  });
  MPI_Allreduce(MPI_IN_PLACE, &m, 1, MPI_DOUBLE, MPI_MIN, comm());
  return m;
}

NodalField Problem::gather(Vec u) const {
  LocalArray ul(dm(), false);
  to_local(u, ul.vec());
  const PetscScalar* a = ul.array();
  const int dim = space_->dim();
  std::vector<double> send;
  std::vector<long long> ids;
  for (const auto& n : space_->owned_nodes()) {
    ids.push_back(n.canonical);
    for (int i = 0; i < dim; ++i) send.push_back(PetscRealPart(a[n.offset + i]));
  }
  const int nr = core::size(comm());
  int n_local = int(ids.size());
  std::vector<int> counts(nr), displs(nr, 0);
  MPI_Gather(&n_local, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, comm());
  for (int r = 1; r < nr; ++r) displs[r] = displs[r - 1] + counts[r - 1];
  const int total = core::rank(comm()) == 0 ? displs[nr - 1] + counts[nr - 1] : 0;
  std::vector<long long> all_ids(total);
  MPI_Gatherv(ids.data(), n_local, MPI_LONG_LONG, all_ids.data(), counts.data(), displs.data(),
              MPI_LONG_LONG, 0, comm());
  for (int r = 0; r < nr; ++r) {
    counts[r] *= dim;
    displs[r] *= dim;
  }
  std::vector<double> all_vals(std::size_t(total) * dim);
  MPI_Gatherv(send.data(), n_local * dim, MPI_DOUBLE, all_vals.data(), counts.data(),
              displs.data(), MPI_DOUBLE, 0, comm());
  NodalField out;
  out.n_components = dim;
  if (core::rank(comm()) == 0) {
    if (total != space_->n_nodes_global())
      throw std::logic_error("gathered node count differs from the mesh's");
    out.values.assign(std::size_t(total) * dim, 0.0);
    for (int k = 0; k < total; ++k)
      for (int i = 0; i < dim; ++i) out.values[std::size_t(all_ids[k]) * dim + i] = all_vals[std::size_t(k) * dim + i];
  }
  return out;
}

core::VecH Problem::scatter(std::vector<double> values) const {
  unsigned long n = values.size();
  MPI_Bcast(&n, 1, MPI_UNSIGNED_LONG, 0, comm());
  values.resize(n);
  MPI_Bcast(values.data(), int(n), MPI_DOUBLE, 0, comm());
  const int d = space_->dim();
  if (n != std::size_t(space_->n_nodes_global()) * std::size_t(d))
    throw std::logic_error("Problem::scatter: the field's size differs from the mesh's nodes");
  LocalArray ul(dm(), true);
  PetscScalar* a = ul.array();
  for (const auto& node : space_->owned_nodes())
    for (int k = 0; k < d; ++k) a[node.offset + k] = values[std::size_t(node.canonical * d + k)];
  core::VecH u = create_vector();
  ul.release();
  HS_PETSC(DMLocalToGlobal(dm(), ul.vec(), INSERT_VALUES, u));  // the owned nodes; constrained dofs drop out
  return u;
}

core::MatH Problem::create_matrix() const {
  // The pattern once per problem (Space::create_matrix); a copy of it costs a memcpy.
  if (!pattern_) pattern_ = space_->create_matrix();
  core::MatH J;
  HS_PETSC(MatDuplicate(pattern_, MAT_DO_NOT_COPY_VALUES, J.out()));
  if (!conservative()) return J;  // a follower load's stiffness is not symmetric
  HS_PETSC(MatSetOption(J, MAT_SYMMETRIC, PETSC_TRUE));
  HS_PETSC(MatSetOption(J, MAT_SYMMETRY_ETERNAL, PETSC_TRUE));
  return J;
}

core::VecH Problem::create_vector() const {
  core::VecH v;
  HS_PETSC(DMCreateGlobalVector(dm(), v.out()));
  HS_PETSC(VecZeroEntries(v));
  return v;
}

}  // namespace hypershape::physics
