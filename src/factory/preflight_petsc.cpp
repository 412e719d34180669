#include <fmt/format.h>
#include <petscsys.h>

#include "hypershape/core/error.hpp"
#include "hypershape/factory/dataset_scene.hpp"
#include "hypershape/factory/label_error.hpp"
#include "hypershape/factory/preflight.hpp"
#include "hypershape/mesh/gmsh_mesher.hpp"
#include "hypershape/solver/nonlinear.hpp"

namespace hypershape::factory {

namespace {

/// The dataset's scene on a coarse disk / ball: clamp at (-1, 0, 0), traction at (1, 0, 0)
/// pushing along y, one target solve at the low end of the target range.
void trial_solve(const config::DatasetConfig& cfg) {
  const int d = cfg.shapes.dim;
  ShapeSample shape;
  shape.dirichlet_center = {-1.0, 0.0, 0.0};
  shape.dirichlet_radius = std::min(cfg.shapes.dirichlet_radius, 1.0);
  mesh::MeshOptions mo;
  mo.h = d == 2 ? 0.3 : 0.6;
  const mesh::ClampRegion clamp{shape.dirichlet_center, shape.dirichlet_radius};
  shape.mesh = d == 2 ? mesh::mesh_disk(mo, clamp) : mesh::mesh_ball(mo, clamp);
  LoadCase lc;
  lc.center = {1.0, 0.0, 0.0};
  lc.direction = {0.0, 1.0, 0.0};
  lc.target = cfg.loads.target_min;
  const auto n = std::size_t(std::max(0, n_tractions(cfg) - 1));
  lc.more_centers.assign(n, lc.center);
  lc.more_directions.assign(n, lc.direction);
  ShapeProblem sp = make_shape_problem(PETSC_COMM_SELF, cfg, shape, lc);
  solver::NonlinearSolver nl(*sp.problem, cfg.solver);
  const auto r = nl.solve_for_target(lc.target);
  // The labels' error estimate (when the dataset asks for it) reads -error_estimate_order and
  // the -error_estimate_ksp_* options.
  LabelErrors errors(cfg, 1);
  if (r.converged && errors.enabled())
    errors.estimate(PETSC_COMM_SELF, cfg, shape, lc, lc, *sp.problem, nl.solution(), r.alpha,
                    [&](Vec x, Vec y, bool refined) { return nl.apply_tangent_factor(x, y, refined); });
}

/// Options PETSc reads only in PetscFinalize (or at start-up, for the whole process): no
/// object of a trial solve asks for them.
bool read_at_finalize(const std::string& name) {
  for (const char* p : {"-options_left", "-options_view", "-malloc", "-memory_view", "-objects_dump", "-log_",
                        "-info", "-on_error_"})
    if (name.rfind(p, 0) == 0) return true;
  return false;
}

std::string listed(const std::vector<UserOption>& options) {
  std::string s;
  for (const auto& o : options) s += (s.empty() ? "" : ", ") + o.name + " (" + o.origin + ")";
  return s;
}

}  // namespace

void check_petsc_options(const config::DatasetConfig& cfg, const std::vector<UserOption>& options) {
  solver::set_default_options(cfg.petsc);
  if (options.empty()) return;  // the defaults are the project's own: nothing to check
  HS_PETSC(PetscPushErrorHandler(PetscReturnErrorHandler, nullptr));
  try {
    trial_solve(cfg);
  } catch (const core::PetscError& e) {
    PetscPopErrorHandler();
    const char* text = nullptr;
    char* specific = nullptr;
    PetscErrorMessage(e.code(), &text, &specific);
    throw core::InputError(cfg.source, "petsc",
                           fmt::format("PETSc rejected the options {} in a trial set-up: {}{}", listed(options),
                                       text ? text : "", specific ? std::string(": ") + specific : ""));
  }
  PetscPopErrorHandler();
  for (const auto& o : options) {
    if (read_at_finalize(o.name)) continue;
    PetscBool used = PETSC_FALSE;
    HS_PETSC(PetscOptionsUsed(nullptr, o.name.c_str() + 1, &used));  // stored without the dash
    if (!used)
      throw core::InputError(o.origin == "command line" ? "" : cfg.source, o.origin,
                             fmt::format("{}: no PETSc object of this run reads this option (a trial set-up and "
                                         "solve of the dataset's scene did not ask for it): misspelt, or for "
                                         "another solver type; see `-help`", o.name));
  }
}

}  // namespace hypershape::factory
