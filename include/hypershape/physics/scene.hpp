#pragma once
/// A scene's effects: the one description of what is solved. `hypershape solve`, `hypershape
/// generate` and the accuracy study all build their problem from one through build_problem().
///
/// A SceneSpec lists effects (an effect may appear several times, e.g. two tractions) with
/// their parameters; a numeric parameter is a number or a Draw (uniform, log-uniform, choice),
/// drawn per shape or per load case by the factory. resolve() turns a spec into ResolvedEffects
/// (numbers only), which build_effects() / build_problem() turn into effects.
#include <mpi.h>

#include <functional>
#include <map>
#include <optional>
#include <memory>
#include <set>
#include <string>
#include <variant>
#include <vector>

#include "hypershape/core/params.hpp"
#include "hypershape/mesh/mesh_data.hpp"
#include "hypershape/physics/effect.hpp"
#include "hypershape/physics/problem.hpp"

namespace hypershape::physics {

/// A number drawn from a distribution, once per shape or once per load case.
struct Draw {
  enum class Kind { uniform, log_uniform, choice };
  enum class Per { shape, load };
  Kind kind = Kind::uniform;
  std::vector<double> values;  ///< [a, b] (uniform, log_uniform) or the choices
  Per per = Per::shape;
  /// One value from a uniform variate u in [0, 1).
  double at(double u) const;
  double low() const;
  double high() const;
  /// "uniform [a, b] per shape", for messages and reports.
  std::string describe() const;
};

using ParamValue = std::variant<double, std::vector<double>, std::string, Draw>;

/// One effect of a scene as written: name, key path in its file, parameters.
struct EffectSpec {
  std::string name;   ///< a registered effect (registry.hpp)
  std::string label;  ///< name, or name.k for the k-th entry of a list (stored arrays use it)
  std::string path;   ///< key path in the file, e.g. "effects.gaussian_traction[1]"
  std::map<std::string, ParamValue> params;
  bool scaled = true; ///< a load: scaled by the load factor (scale: alpha) or fixed (scale: fixed)
  bool scale_given = false;
  /// `count: {choice: [1, 2, 3], sample: load}`: the effect is copies 0..max-1 (labels name.k)
  /// and copy k is active where k < the count drawn (per shape or load case).
  std::optional<Draw> count;
  int copy = 0;
};

struct SceneSpec {
  std::string source;  ///< the file, for messages
  std::vector<EffectSpec> effects;
  /// Indices of the effects with this name, in order.
  std::vector<std::size_t> find(const std::string& name) const;
};

/// The parameters of one effect with every number fixed. Keys read are remembered, so that an
/// unknown key is reported (check_all_used). Errors name the file and the key path.
class EffectParams : public core::Params {
 public:
  using Value = std::variant<double, std::vector<double>, std::string>;
  EffectParams(std::string file, std::string path) : file_(std::move(file)), path_(std::move(path)) {}
  EffectParams& set(const std::string& key, Value v) {
    values_[key] = std::move(v);
    return *this;
  }
  bool has(const std::string& key) const override;
  double number(const std::string& key) const override;
  std::vector<double> vector(const std::string& key, std::size_t n) const override;
  std::string text(const std::string& key) const override;
  [[noreturn]] void fail(const std::string& key, const std::string& message) const override;
  /// Throws InputError for a key no effect read.
  void check_all_used() const;
  const std::map<std::string, Value>& values() const { return values_; }

 private:
  std::map<std::string, Value> values_;
  std::string file_, path_;
  mutable std::set<std::string> used_;
};

struct ResolvedEffect {
  std::string name;
  EffectParams params;
  bool scaled = true;
  bool scale_given = false;
  bool active = true;  ///< false: built but contributes nothing (EffectSpec::count)
};

/// Supplies the value of a drawn parameter: (effect index, key, its draw) -> number.
using DrawFn = std::function<double(std::size_t effect, const std::string& key, const Draw& draw)>;
/// Fixes every Draw of `spec` through `draw`; extra (key, value) pairs the caller computes
/// (e.g. a traction centre drawn on the boundary) are added per effect by `extra`.
std::vector<ResolvedEffect> resolve(
    const SceneSpec& spec, const DrawFn& draw,
    const std::function<void(std::size_t effect, EffectParams& params)>& extra = {});

/// Builds one effect (its keys checked, its scale set). Throws core::InputError.
EffectPtr build_effect(const ResolvedEffect& effect, int dim);

/// Builds every effect, checking its keys, and that the whole makes one solvable problem:
/// exactly one material (an effect with a stored energy), at least one Dirichlet condition,
/// `scale` only on loads, a scaled load when `needs_scaled_load` (a tuned alpha needs one).
/// Throws core::InputError naming the file and the effect's key path. Not collective.
std::vector<EffectPtr> build_effects(const std::string& source, const std::vector<ResolvedEffect>& effects,
                                     int dim, bool needs_scaled_load);

/// The one problem builder: the effects of a resolved scene on `mesh` (read on rank 0 of
/// `comm`). Effects are validated (build_effects) on every rank before any collective work.
/// Collective.
std::unique_ptr<Problem> build_problem(MPI_Comm comm, const mesh::MeshData& mesh, const std::string& source,
                                       const std::vector<ResolvedEffect>& effects, int dim,
                                       const SpaceOptions& space, bool needs_scaled_load);

}  // namespace hypershape::physics
