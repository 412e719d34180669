#pragma once
/// PETSc log events of the nonlinear solver's pieces, so that -log_view explains a load case:
/// HSTangentAsm (tangent assemblies), HSFactor (numeric factorisations, symbolic included on
/// the first), HSFactorSolve (direct solves with a factor), HSKrylov (Newton-Krylov solves),
/// HSPredictor / HSCorrector (the displacement-controlled path), HSBranchSwitch, HSLoadControl,
/// HSAMGSetup (multigrid set-ups of a tangent), HSStability (the multigrid kind's LOBPCG check),
/// HSFactorSingle (numeric single-precision factorisations, SMUMPS: not a PCSetUp),
/// HSFactorBlocked (numeric factorisations of the 2D blocked LDL^T, BlockLdlt2: not a PCSetUp);
/// the labels' error estimate (TwoLevelEstimator): HSEstimate (one estimate), within it
/// HSEstFineAsm (fine residuals, tangents, energies), HSEstFineSolve (the two-grid GMRES) and
/// HSEstValues (the estimates from the fields: gathers, norms).
#include <petsclog.h>

namespace hypershape::solver {

struct Events {
  PetscLogEvent tangent_assembly, factorisation, factor_solve, krylov, predictor, corrector,
      branch_switch, load_control, multigrid_setup, stability, single_factor, blocked_factor, relaxation;
  PetscLogEvent estimate, estimate_fine_assembly, estimate_fine_solve, estimate_values;
};

/// Registered on first use (PETSc must be initialised). Not collective.
const Events& events();

/// Begins an event for the lifetime of the scope.
class LogEvent {
 public:
  explicit LogEvent(PetscLogEvent e) : e_(e) { PetscLogEventBegin(e_, 0, 0, 0, 0); }
  ~LogEvent() { PetscLogEventEnd(e_, 0, 0, 0, 0); }
  LogEvent(const LogEvent&) = delete;
  LogEvent& operator=(const LogEvent&) = delete;

 private:
  PetscLogEvent e_;
};

}  // namespace hypershape::solver
