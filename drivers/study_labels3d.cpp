/// study_labels3d: how far a 3D label is from a converged reference, and what it costs
/// (issue 16 part B; docs/ACCURACY.md, "3D labels").
///
/// One load case of a 3D scene with the random3d preset's problem (neo-Hookean E 500, nu 0.49,
/// clamp patch r 0.4, Gaussian traction gamma 0.1): the unit ball (p_D = (1, 0, 0), p_N =
/// (-1, 0, 0), g = (0, 1, 0)) or Random3D shape 0 (its p_D and load case 0). Every
/// discretisation is solved at the same traction scale alpha (load control) and compared with the
/// reference on the label's vertices (the discretisation's own, or with label_on the stored
/// shape's mesh a per-load-case mesh is sampled onto). Discretisations:
///   name:key=value,...  keys h (surface and interior), surface_h, interior_h, rim (edge at the
///   clamp rim), load (edge at p_N: a per-load-case mesh), grading (size growth per unit
///   distance, default 0.3), label_on (the stored mesh, for load-refined ones)
/// Sample run (one rank; the table in docs/ACCURACY.md is scripts/study_labels3d.sh):
///   study_labels3d --scene ball --reference ref -d ref:surface_h=0.1,interior_h=0.2,rim=0.0125,load=0.0125
///       -d u0.3:h=0.3 --out results/labels3d_ball.json
#include <CLI/CLI.hpp>

#include <iostream>

#include "hypershape/core/petsc_handle.hpp"
#include "hypershape/mesh/gmsh_mesher.hpp"
#include "hypershape/study/labels3d.hpp"
#include "hypershape/study/output.hpp"

namespace hs = hypershape;

int main(int argc, char** argv) {
  auto [ours, petsc] = hs::study::split_at_dashes(argc, argv);
  hs::study::labels3d::Options o;
  std::vector<std::string> specs;
  std::string out = "results/labels3d.json";
  CLI::App app{"3D label error against a converged reference (docs/ACCURACY.md). Arguments after \"--\" go to PETSc."};
  app.add_option("--scene", o.scene, "ball | r3d-0 | r3d:SEED:SHAPE:LOAD (a load case of the random3d preset's factory)");
  app.add_option("--alpha", o.alpha, "traction scale (default 5)")->check(CLI::PositiveNumber);
  app.add_option("--reference", o.reference, "name of the reference discretisation")->required();
  app.add_option("-d,--discretisation", specs, "name:key=value,... (see the source header)")->required();
  app.add_option("--loads-per-shape", o.loads_per_shape, "per-shape costs are shared by this many load cases");
  app.add_flag("--time-target", o.time_target, "also time solve_for_target at the reference's max|u| (the factory's path)");
  app.add_option("--out", out, "JSON results");
  app.add_option("--write", o.write_dir, "write every solution to DIR/<scene>_<name>.h5 (scripts/check_labels3d_dolfinx.py reads them)");
  try {
    app.parse(ours.count(), ours.data());
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  if (!hs::study::output_writable(out, "--out")) return 2;
  int petsc_argc = petsc.count();
  char** petsc_argv = petsc.data();
  try {
    for (const auto& s : specs) o.discretisations.push_back(hs::study::labels3d::parse_discretisation(s));
    hs::core::PetscSession session(&petsc_argc, &petsc_argv, "study_labels3d (see the source header)\n");
    hs::mesh::GmshSession gmsh;
    hs::study::write_json_atomic(out, hs::study::labels3d::run(o), "--out", 1);
    std::cerr << "[labels3d] " << out << "\n";
  } catch (const std::exception& e) {
    std::cerr << "[rank 0] study_labels3d: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
