#pragma once
/// Wall-clock time per named phase (meshing, set-up, solve, ...), accumulated.
#include <chrono>
#include <map>
#include <string>

namespace hypershape::core {

class PhaseTimes {
 public:
  /// RAII scope that adds its lifetime to phase `name`.
  class Scope {
   public:
    Scope(PhaseTimes& t, std::string name)
        : t_(t), name_(std::move(name)), start_(std::chrono::steady_clock::now()) {}
    ~Scope() {
      t_.add(name_, std::chrono::duration<double>(std::chrono::steady_clock::now() - start_)
                        .count());
    }

   private:
    PhaseTimes& t_;
    std::string name_;
    std::chrono::steady_clock::time_point start_;
  };

  Scope scope(std::string name) { return Scope(*this, std::move(name)); }
  void add(const std::string& name, double seconds) { seconds_[name] += seconds; }
  double get(const std::string& name) const {
    auto it = seconds_.find(name);
    return it == seconds_.end() ? 0.0 : it->second;
  }
  const std::map<std::string, double>& all() const { return seconds_; }

 private:
  std::map<std::string, double> seconds_;
};

/// Seconds since an arbitrary epoch (steady clock).
inline double now_seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

}  // namespace hypershape::core
