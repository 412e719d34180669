#pragma once
/// Counter-based random streams: every draw is a pure function of a key built from ids
/// (dataset seed, shape id, load id, purpose, attempt), never of the order in which ranks or
/// SLURM tasks happen to run. The generator is SplitMix64 in counter mode (Steele, Lea and
/// Flood 2014): draw k of stream `key` is mix64(key + (k + 1) * golden), so streams can be
/// created anywhere without state shared between them.
#include <cstdint>
#include <initializer_list>

namespace hypershape::core {

/// The SplitMix64 finaliser: a bijective avalanche mix of 64 bits.
constexpr std::uint64_t mix64(std::uint64_t z) {
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

/// What a stream is used for: part of its key, so that the traction of load 3 never shares
/// numbers with, say, the velocity field of shape 3.
enum class Purpose : std::uint64_t {
  shape = 1,       ///< random deformation of a shape (velocity fields)
  dirichlet = 2,   ///< Dirichlet patch centre p_D
  traction = 3,    ///< traction centre p_N and direction g
  target = 4,      ///< target displacement magnitude of a load case
  split = 5,       ///< train/val/test assignment of shapes
  parameter = 6,   ///< a scene parameter drawn from a distribution (per shape or load case)
  material = 7,    ///< a material's modulus field (its random Fourier modes)
  test = 99,       ///< tests and benchmarks
};

/// Key of the stream for (seed, purpose, ids...): a hash chain, order-sensitive.
constexpr std::uint64_t stream_key(std::uint64_t seed, Purpose purpose,
                                   std::initializer_list<std::uint64_t> ids) {
  std::uint64_t k = mix64(seed ^ 0x6A09E667F3BCC909ULL);
  k = mix64(k ^ (static_cast<std::uint64_t>(purpose) * 0x9E3779B97F4A7C15ULL));
  for (std::uint64_t id : ids) k = mix64(k + 0x9E3779B97F4A7C15ULL + mix64(id));
  return k;
}

/// A stream of uniform and normal variates. Cheap to create; not thread-safe.
class RandomStream {
 public:
  explicit RandomStream(std::uint64_t key) : key_(key) {}
  RandomStream(std::uint64_t seed, Purpose purpose, std::initializer_list<std::uint64_t> ids)
      : key_(stream_key(seed, purpose, ids)) {}

  std::uint64_t next_u64() { return mix64(key_ + (++counter_) * 0x9E3779B97F4A7C15ULL); }
  /// Uniform on [0, 1) with 53 random bits.
  double uniform() { return double(next_u64() >> 11) * 0x1.0p-53; }
  /// Standard normal (Box-Muller; the second variate of each pair is kept for the next call).
  double normal();
  /// Number of 64-bit words drawn so far.
  std::uint64_t n_drawn() const { return counter_; }

 private:
  std::uint64_t key_;
  std::uint64_t counter_ = 0;
  bool has_spare_ = false;
  double spare_ = 0.0;
};

}  // namespace hypershape::core
