#include "log_events.hpp"

#include "hypershape/core/error.hpp"

namespace hypershape::solver {

const Events& events() {
  static const Events e = [] {
    PetscClassId cls;
    HS_PETSC(PetscClassIdRegister("hypershape solver", &cls));
    Events r{};
    HS_PETSC(PetscLogEventRegister("HSTangentAsm", cls, &r.tangent_assembly));
    HS_PETSC(PetscLogEventRegister("HSFactor", cls, &r.factorisation));
    HS_PETSC(PetscLogEventRegister("HSFactorSolve", cls, &r.factor_solve));
    HS_PETSC(PetscLogEventRegister("HSKrylov", cls, &r.krylov));
    HS_PETSC(PetscLogEventRegister("HSPredictor", cls, &r.predictor));
    HS_PETSC(PetscLogEventRegister("HSCorrector", cls, &r.corrector));
    HS_PETSC(PetscLogEventRegister("HSBranchSwitch", cls, &r.branch_switch));
    HS_PETSC(PetscLogEventRegister("HSLoadControl", cls, &r.load_control));
    HS_PETSC(PetscLogEventRegister("HSAMGSetup", cls, &r.multigrid_setup));
    HS_PETSC(PetscLogEventRegister("HSStability", cls, &r.stability));
    HS_PETSC(PetscLogEventRegister("HSFactorSingle", cls, &r.single_factor));
    HS_PETSC(PetscLogEventRegister("HSFactorBlocked", cls, &r.blocked_factor));
    HS_PETSC(PetscLogEventRegister("HSRelax", cls, &r.relaxation));
    HS_PETSC(PetscLogEventRegister("HSEstimate", cls, &r.estimate));
    HS_PETSC(PetscLogEventRegister("HSEstFineAsm", cls, &r.estimate_fine_assembly));
    HS_PETSC(PetscLogEventRegister("HSEstFineSolve", cls, &r.estimate_fine_solve));
    HS_PETSC(PetscLogEventRegister("HSEstValues", cls, &r.estimate_values));
    return r;
  }();
  return e;
}

}  // namespace hypershape::solver
