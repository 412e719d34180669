/// Homogeneous Dirichlet conditions on selected boundary facets, and the effect
/// "dirichlet_patch" of the seed paper: Gamma_D = B_r(p_D) ∩ boundary.
/// Keys: center (p_D, a point), radius (r > 0).
#include <petscdmplex.h>

#include <cmath>

#include "hypershape/core/error.hpp"
#include "hypershape/core/vec_array.hpp"
#include "hypershape/mesh/plex.hpp"
#include "hypershape/physics/registry.hpp"

namespace hypershape::physics {

namespace {

class DirichletEffect : public Effect {
 public:
  DirichletEffect(std::string label, FacetPredicate select, std::vector<PetscInt> components,
                  std::string name)
      : label_(std::move(label)),
        select_(std::move(select)),
        components_(std::move(components)),
        name_(std::move(name)) {}

  std::string name() const override { return name_; }

  void mark(DM serial) override {
    PetscInt dim;
    HS_PETSC(DMGetDimension(serial, &dim));
    if (components_.empty())
      for (PetscInt c = 0; c < dim; ++c) components_.push_back(c);
    HS_PETSC(DMCreateLabel(serial, label_.c_str()));
    DMLabel label;
    HS_PETSC(DMGetLabel(serial, label_.c_str(), &label));
    Vec coords;
    PetscSection cs;
    HS_PETSC(DMGetCoordinatesLocal(serial, &coords));
    HS_PETSC(DMGetCoordinateSection(serial, &cs));
    const core::VecArray<const PetscScalar> xa(coords);
    PetscInt v0, v1;
    HS_PETSC(DMPlexGetDepthStratum(serial, 0, &v0, &v1));
    IS facets = nullptr;
    HS_PETSC(DMGetStratumIS(serial, mesh::boundary_label, 1, &facets));
    long n_marked = 0;
    if (facets) {
      PetscInt nf;
      const PetscInt* fp;
      HS_PETSC(ISGetLocalSize(facets, &nf));
      HS_PETSC(ISGetIndices(facets, &fp));
      for (PetscInt i = 0; i < nf; ++i) {
        PetscInt n, *cl = nullptr;
        double x[9];
        int nv = 0;
        HS_PETSC(DMPlexGetTransitiveClosure(serial, fp[i], PETSC_TRUE, &n, &cl));
        for (PetscInt j = 0; j < n; ++j)
          if (cl[2 * j] >= v0 && cl[2 * j] < v1 && nv < 3) {
            PetscInt off;
            HS_PETSC(PetscSectionGetOffset(cs, cl[2 * j], &off));
            for (PetscInt k = 0; k < dim; ++k) x[nv * dim + k] = PetscRealPart(xa[off + k]);
            ++nv;
          }
        HS_PETSC(DMPlexRestoreTransitiveClosure(serial, fp[i], PETSC_TRUE, &n, &cl));
        if (select_(x, nv, int(dim))) {
          HS_PETSC(DMLabelSetValue(label, fp[i], 1));
          ++n_marked;
        }
      }
      HS_PETSC(ISRestoreIndices(facets, &fp));
      HS_PETSC(ISDestroy(&facets));
    }
    MPI_Allreduce(MPI_IN_PLACE, &n_marked, 1, MPI_LONG, MPI_SUM, PetscObjectComm((PetscObject)serial));
    if (n_marked == 0)
      throw core::InputError("", name_, "selects no boundary facet of the mesh (nothing is fixed)");
    HS_PETSC(DMPlexLabelComplete(serial, label));
  }

  std::vector<EssentialBC> essential_bcs() const override { return {{label_, components_}}; }

 private:
  std::string label_;
  FacetPredicate select_;
  std::vector<PetscInt> components_;
  std::string name_;
};

}  // namespace

EffectPtr make_dirichlet(std::string label_name, FacetPredicate select,
                         std::vector<PetscInt> components) {
  std::string name = label_name;
  return std::make_unique<DirichletEffect>(std::move(label_name), std::move(select),
                                           std::move(components), std::move(name));
}

EffectPtr make_dirichlet_patch(const std::vector<double>& center, double radius) {
  // Facets whose vertices all lie within r of p_D. The mesher puts vertices exactly at the patch
  // ends, so on such meshes this is exactly B_r(p_D) ∩ boundary.
  const double tol = 1e-9 * std::max(1.0, radius);
  auto select = [center, radius, tol](const double* x, int nv, int dim) {
    for (int a = 0; a < nv; ++a) {
      double d2 = 0;
      for (int k = 0; k < dim; ++k) d2 += (x[a * dim + k] - center[k]) * (x[a * dim + k] - center[k]);
      if (std::sqrt(d2) > radius + tol) return false;
    }
    return true;
  };
  return std::make_unique<DirichletEffect>("dirichlet_patch", select, std::vector<PetscInt>{},
                                           "dirichlet_patch");
}

void register_dirichlet_patch() {
  register_effect(
      "dirichlet_patch",
      [](const core::Params& p, int dim) {
        auto c = p.vector("center", std::size_t(dim));
        const double r = p.number_in("radius", 0.0, 1e300, true);
        return make_dirichlet_patch(c, r);
      },
      "u = 0 on the boundary within distance r of p_D; keys: center (p_D), radius (r > 0)");
}

}  // namespace hypershape::physics
