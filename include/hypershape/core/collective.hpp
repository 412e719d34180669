#pragma once
/// Runs work on rank 0 and makes a failure there a failure everywhere: the exception's message
/// is broadcast and every rank throws, so no rank is left waiting in a collective.
#include <mpi.h>

#include <string>

#include "hypershape/core/error.hpp"

namespace hypershape::core {

/// Calls `fn()` on rank 0 of `comm` only. If it throws, every rank throws: InputError (with the
/// same file/key text) for input errors, std::runtime_error otherwise. Collective.
template <class Fn>
void on_root(MPI_Comm comm, Fn&& fn) {
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  int kind = 0;  // 0 ok, 1 input error, 2 other
  std::string msg, file, key;
  if (rank == 0) {
    try {
      fn();
    } catch (const InputError& e) {
      kind = 1;
      file = e.file();
      key = e.key();
      msg = e.what();
    } catch (const std::exception& e) {
      kind = 2;
      msg = e.what();
    }
  }
  MPI_Bcast(&kind, 1, MPI_INT, 0, comm);
  if (kind == 0) return;
  int n = int(msg.size());
  MPI_Bcast(&n, 1, MPI_INT, 0, comm);
  msg.resize(n);
  MPI_Bcast(msg.data(), n, MPI_CHAR, 0, comm);
  if (kind == 1) throw InputError("", "", msg);
  throw std::runtime_error(msg);
}

}  // namespace hypershape::core
