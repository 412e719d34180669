#include "hypershape/core/petsc_handle.hpp"

#include "hypershape/core/error.hpp"

namespace hypershape::core {

PetscSession::PetscSession(int* argc, char*** argv, const char* help) {
  HS_PETSC(PetscInitialize(argc, argv, nullptr, help));
}

PetscSession::~PetscSession() { PetscFinalize(); }

int rank(MPI_Comm comm) {
  int r = 0;
  MPI_Comm_rank(comm, &r);
  return r;
}

int size(MPI_Comm comm) {
  int s = 1;
  MPI_Comm_size(comm, &s);
  return s;
}

}  // namespace hypershape::core
