#pragma once
/// Internal gmsh helpers shared by the src/mesh/*.cpp files (not installed; gmsh.h stays inside
/// src/mesh/).
#include <gmsh.h>

#include <optional>
#include <string>

#include "hypershape/mesh/gmsh_mesher.hpp"

namespace hypershape::mesh::detail {

/// After gmsh throws inside open()/merge() it stays locked ("I'm busy!") and keeps its last
/// error: restart it so later meshing works.
inline void restart_gmsh() {
  try {
    gmsh::finalize();
  } catch (...) {
  }
  gmsh::initialize(0, nullptr, false);
  gmsh::option::setNumber("General.Terminal", 0);
}

/// A gmsh model for the duration of one call, inside a session opened here unless one is
/// already open; the model is removed on exit.
class ScopedModel {
 public:
  explicit ScopedModel(const std::string& name) {
    // gmsh keeps state from one model to the next (measured: the same boundary gave 1405 or
    // 1400 vertices depending on what the process had meshed before), which would make a
    // shape depend on the ranks and the schedule. Every model starts from a fresh gmsh.
    if (!GmshSession::active()) own_.emplace();
    else restart_gmsh();
    gmsh::model::add(name);
    gmsh::model::setCurrent(name);
  }
  ScopedModel(const ScopedModel&) = delete;
  ScopedModel& operator=(const ScopedModel&) = delete;
  ~ScopedModel() {
    try {
      gmsh::model::remove();
    } catch (...) {
    }
  }

 private:
  std::optional<GmshSession> own_;
};

/// gmsh's last logged error ("" if none). gmsh keeps it across calls: compare with the value
/// before a call to see whether that call failed.
inline std::string last_gmsh_error() {
  std::string err;
  try {
    gmsh::logger::getLastError(err);
  } catch (...) {
  }
  return err;
}

}  // namespace hypershape::mesh::detail
