/// Test main for both test binaries: a PETSc session (and so MPI) and one gmsh session around
/// Catch's. Catch's arguments are not shown to PETSc (it would store "-#" and friends as
/// options); pass PETSc options through the PETSC_OPTIONS environment variable instead.
#define CATCH_CONFIG_RUNNER
#include <catch2/catch.hpp>

#include "hypershape/core/log.hpp"
#include "hypershape/core/petsc_handle.hpp"
#include "hypershape/mesh/gmsh_mesher.hpp"

int main(int argc, char** argv) {
  int petsc_argc = 1;
  char** petsc_argv = argv;
  hypershape::core::PetscSession petsc(&petsc_argc, &petsc_argv, nullptr);
  hypershape::core::set_verbosity(hypershape::core::Verbosity::quiet);
  hypershape::mesh::GmshSession gmsh;
  Catch::Session session;
  if (const int rc = session.applyCommandLine(argc, argv); rc != 0) return rc;
  return session.run();
}
