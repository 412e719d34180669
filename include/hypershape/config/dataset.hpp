#pragma once
/// A dataset config: which shapes (and, later, which load cases) a dataset holds.
///
/// ```yaml
/// name: random2d
/// seed: 1001                      # every random draw is a function of (seed, shape id, ...)
/// shapes:
///   count: 1000
///   dim: 2                        # 2 | 3
///   base: circle                  # circle (2D) | sphere (3D) | file (3D, + base_file: PATH)
///   steps: [[0.2, 4], [0.1, 1]]   # (sigma, m) per deformation, coarse first
///   velocity_unit: 0.04           # velocity std = m * velocity_unit (optional)
///   nodes_per_sigma: 6            # velocity grid resolution (optional; 6 in 2D, 3 in 3D)
///   h: 0.04                       # element size, in the normalised box [-1, 1]^d
///   dirichlet_radius: 0.5         # r (0: no Dirichlet patch)
///   max_turn_deg: 15              # optional, 2D boundary resolution
///   min_feature_fraction: 0.1     # optional: redraw shapes with necks thinner than this * h
///   max_attempts: 20              # optional
///   quality: {min_angle_deg: 18, min_shape: 0.3}   # optional mesh gate
/// ```
/// Every key is checked; errors name the file and the key path (core::InputError).
#include <cstdint>
#include <string>

#include "hypershape/factory/shape_pipeline.hpp"

namespace hypershape::config {

struct DatasetConfig {
  std::string source;  ///< file name
  std::string text;    ///< the YAML as read (stored with the data)
  std::string name;
  std::uint64_t seed = 0;
  std::int64_t n_shapes = 0;
  factory::ShapeConfig shapes;
};

/// Parses and validates a dataset config; relative paths (base_file) are resolved against the
/// file's directory. Throws core::InputError.
DatasetConfig parse_dataset_file(const std::string& path);
DatasetConfig parse_dataset_text(const std::string& text, const std::string& source,
                                 const std::string& base_dir = ".");

}  // namespace hypershape::config
