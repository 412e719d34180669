#include <catch2/catch.hpp>

#include <string>

#include "hypershape/study/output.hpp"

namespace hs = hypershape;

TEST_CASE("Driver command lines split at \"--\" into null-terminated argument vectors", "[study]") {
  // MPI_Init (Open MPI) walks argv up to its null pointer: a vector without one was read past
  // its end, and study_error_estimate crashed inside PetscInitialize when given PETSc options.
  std::string a0 = "driver", a1 = "--out", a2 = "x.jsonl", dd = "--", p1 = "-ksp_rtol", p2 = "0.1";
  char* argv[] = {a0.data(), a1.data(), a2.data(), dd.data(), p1.data(), p2.data(), nullptr};
  auto [ours, petsc] = hs::study::split_at_dashes(6, argv);
  REQUIRE(ours.count() == 3);
  REQUIRE(petsc.count() == 3);
  CHECK(std::string(ours.data()[0]) == "driver");
  CHECK(std::string(ours.data()[2]) == "x.jsonl");
  CHECK(std::string(petsc.data()[0]) == "driver");
  CHECK(std::string(petsc.data()[1]) == "-ksp_rtol");
  CHECK(std::string(petsc.data()[2]) == "0.1");
  CHECK(ours.data()[ours.count()] == nullptr);
  CHECK(petsc.data()[petsc.count()] == nullptr);
  // Nothing after "--": PETSc gets argv[0] alone, still terminated.
  auto [only, none] = hs::study::split_at_dashes(3, argv);
  CHECK(only.count() == 3);
  CHECK(none.count() == 1);
  CHECK(none.data()[1] == nullptr);
}
