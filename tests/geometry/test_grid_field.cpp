// Gaussian-random-field velocities and their flows: statistics of the samples against the
// kernel, interpolation order, and scaling-and-squaring convergence and inversion.
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <vector>

#include "hypershape/core/random.hpp"
#include "hypershape/geometry/grid_field.hpp"

using namespace hypershape;
using geometry::Grid;
using geometry::GridField;

namespace {

Grid square_grid(int dim, double half, double spacing) {
  const double lo[3] = {-half, -half, -half}, hi[3] = {half, half, half};
  return Grid::covering(dim, {lo, std::size_t(dim)}, {hi, std::size_t(dim)}, spacing);
}

std::int64_t node_index(const Grid& g, int i, int j, int k = 0) {
  return i + std::int64_t(g.n[0]) * (j + std::int64_t(g.n[1]) * k);
}

}  // namespace

TEST_CASE("GRF samples have zero mean and the Gaussian covariance", "[geometry][grf]") {
  const double sigma = 0.2, m = 1.7;
  const Grid g = square_grid(2, 0.5, 0.05);  // 21 x 21 nodes
  const int c = g.n[0] / 2;
  // Pairs (centre, centre + s nodes along x, y or diagonally) at several distances.
  struct Pair {
    std::int64_t a, b;
    double distance;
  };
  std::vector<Pair> pairs;
  for (int s : {0, 1, 2, 4, 6}) {
    pairs.push_back({node_index(g, c, c), node_index(g, c + s, c), s * g.spacing});
    pairs.push_back({node_index(g, c - s, c), node_index(g, c, c + s), std::sqrt(2.0) * s * g.spacing});
  }
  const int n_samples = 4000;
  std::vector<double> mean(pairs.size(), 0.0), cov(pairs.size(), 0.0), cross(pairs.size(), 0.0);
  for (int s = 0; s < n_samples; ++s) {
    core::RandomStream rng(7, core::Purpose::test, {std::uint64_t(s)});
    const GridField v = geometry::sample_velocity_field(g, sigma, m, rng);
    for (std::size_t p = 0; p < pairs.size(); ++p) {
      const double va = v.at(pairs[p].a, 0), vb = v.at(pairs[p].b, 0);
      const double wb = v.at(pairs[p].b, 1);
      mean[p] += va;
      cov[p] += va * vb;
      cross[p] += va * wb;
    }
  }
  const double var = m * m;
  for (std::size_t p = 0; p < pairs.size(); ++p) {
    mean[p] /= n_samples;
    cov[p] /= n_samples;
    cross[p] /= n_samples;
    const double d = pairs[p].distance;
    const double exact = var * std::exp(-d * d / (2 * sigma * sigma));
    // Standard deviation of the sample covariance of two jointly Gaussian variables.
    const double sd_cov = std::sqrt((var * var + exact * exact) / n_samples);
    INFO("distance " << d << ": covariance " << cov[p] << " vs kernel " << exact);
    CHECK(std::abs(mean[p]) < 4.5 * m / std::sqrt(double(n_samples)));
    CHECK(std::abs(cov[p] - exact) < 4.5 * sd_cov);
    // Components are independent.
    CHECK(std::abs(cross[p]) < 4.5 * std::sqrt(var * var / n_samples));
  }
}

TEST_CASE("3D GRF samples match the kernel", "[geometry][grf]") {
  const double sigma = 0.15, m = 0.5;
  const Grid g = square_grid(3, 0.3, 0.05);  // 13^3 nodes
  const int c = g.n[0] / 2;
  const std::int64_t a = node_index(g, c, c, c);
  const std::int64_t b = node_index(g, c, c + 2, c + 1);  // distance sqrt(5) * 0.05
  const int n_samples = 3000;
  double caa = 0, cab = 0;
  for (int s = 0; s < n_samples; ++s) {
    core::RandomStream rng(11, core::Purpose::test, {std::uint64_t(s)});
    const GridField v = geometry::sample_velocity_field(g, sigma, m, rng);
    caa += v.at(a, 2) * v.at(a, 2);
    cab += v.at(a, 2) * v.at(b, 2);
  }
  caa /= n_samples;
  cab /= n_samples;
  const double d2 = 5 * 0.05 * 0.05;
  const double exact = m * m * std::exp(-d2 / (2 * sigma * sigma));
  CHECK(std::abs(caa - m * m) < 4.5 * std::sqrt(2.0 / n_samples) * m * m);
  CHECK(std::abs(cab - exact) < 4.5 * std::sqrt((m * m * m * m + exact * exact) / n_samples));
}

TEST_CASE("random streams are pure functions of their ids", "[core][random]") {
  core::RandomStream a(5, core::Purpose::shape, {3, 0}), b(5, core::Purpose::shape, {3, 0});
  core::RandomStream c(5, core::Purpose::shape, {3, 1}), d(5, core::Purpose::dirichlet, {3, 0});
  for (int i = 0; i < 100; ++i) REQUIRE(a.next_u64() == b.next_u64());
  core::RandomStream a2(5, core::Purpose::shape, {3, 0});
  int same_c = 0, same_d = 0;
  for (int i = 0; i < 100; ++i) {
    const auto x = a2.next_u64();
    same_c += x == c.next_u64();
    same_d += x == d.next_u64();
  }
  CHECK(same_c == 0);
  CHECK(same_d == 0);
  // Normal variates: mean 0, variance 1.
  core::RandomStream n(1, core::Purpose::test, {});
  double s1 = 0, s2 = 0;
  const int count = 200000;
  for (int i = 0; i < count; ++i) {
    const double z = n.normal();
    s1 += z;
    s2 += z * z;
  }
  CHECK(std::abs(s1 / count) < 5.0 / std::sqrt(double(count)));
  CHECK(std::abs(s2 / count - 1.0) < 5.0 * std::sqrt(2.0 / count));
}

TEST_CASE("Catmull-Rom interpolation is third order", "[geometry][grf]") {
  const double sigma = 0.2;
  auto f = [&](const double* x) {
    return std::exp(-((x[0] - 0.1) * (x[0] - 0.1) + (x[1] + 0.05) * (x[1] + 0.05)) / (2 * sigma * sigma));
  };
  std::vector<double> errors;
  for (double spacing : {sigma / 2, sigma / 4, sigma / 8}) {
    const Grid g = square_grid(2, 1.0, spacing);
    GridField field(g);
    double x[3];
    for (std::int64_t i = 0; i < g.n_nodes(); ++i) {
      field.node_coords(i, x);
      field.at(i, 0) = f(x);
      field.at(i, 1) = 2.0 * f(x);
    }
    core::RandomStream rng(3, core::Purpose::test, {});
    double err = 0.0, val[2];
    for (int k = 0; k < 2000; ++k) {
      x[0] = -0.6 + 1.2 * rng.uniform();
      x[1] = -0.6 + 1.2 * rng.uniform();
      field.evaluate(x, val);
      err = std::max({err, std::abs(val[0] - f(x)), std::abs(val[1] - 2.0 * f(x)) / 2.0});
    }
    errors.push_back(err);
  }
  INFO("errors " << errors[0] << " " << errors[1] << " " << errors[2]);
  CHECK(errors[1] < 5e-3);  // the default: 4 nodes per sigma
  CHECK(std::log2(errors[1] / errors[2]) > 2.7);
  CHECK(std::log2(errors[0] / errors[1]) > 2.5);
}

namespace {

/// A smooth velocity: a sum of 30 Gaussian bumps of width sigma with random vector weights
/// (itself a Gaussian-kernel field), known in closed form everywhere.
struct BumpVelocity {
  double sigma = 0.2, amplitude = 0.1;
  std::vector<std::array<double, 4>> bumps;  // centre x, y, weight x, y
  BumpVelocity() {
    core::RandomStream r(5, core::Purpose::test, {});
    for (int i = 0; i < 30; ++i)
      bumps.push_back({-1.5 + 3 * r.uniform(), -1.5 + 3 * r.uniform(), r.normal(), r.normal()});
  }
  void operator()(const double* x, double* v) const {
    v[0] = v[1] = 0.0;
    for (const auto& b : bumps) {
      const double d2 = (x[0] - b[0]) * (x[0] - b[0]) + (x[1] - b[1]) * (x[1] - b[1]);
      const double g = amplitude * std::exp(-d2 / (2 * sigma * sigma));
      v[0] += g * b[2];
      v[1] += g * b[3];
    }
  }
  GridField on_grid(double spacing) const {
    const Grid g = square_grid(2, 2.0, spacing);
    GridField field(g);
    double x[3], w[2];
    for (std::int64_t i = 0; i < g.n_nodes(); ++i) {
      field.node_coords(i, x);
      (*this)(x, w);
      field.at(i, 0) = w[0];
      field.at(i, 1) = w[1];
    }
    return field;
  }
  /// The time-1 flow by RK4 with 4096 steps.
  std::array<double, 2> flow(std::array<double, 2> x) const {
    const int n_steps = 4096;
    const double dt = 1.0 / n_steps;
    double k1[2], k2[2], k3[2], k4[2], y[2];
    for (int s = 0; s < n_steps; ++s) {
      (*this)(x.data(), k1);
      y[0] = x[0] + 0.5 * dt * k1[0], y[1] = x[1] + 0.5 * dt * k1[1];
      (*this)(y, k2);
      y[0] = x[0] + 0.5 * dt * k2[0], y[1] = x[1] + 0.5 * dt * k2[1];
      (*this)(y, k3);
      y[0] = x[0] + dt * k3[0], y[1] = x[1] + dt * k3[1];
      (*this)(y, k4);
      for (int a = 0; a < 2; ++a) x[a] += dt / 6.0 * (k1[a] + 2 * k2[a] + 2 * k3[a] + k4[a]);
    }
    return x;
  }
};

/// Largest distance between x + u(x) and the reference images.
double flow_error(const GridField& u, const std::vector<std::array<double, 2>>& start,
                  const std::vector<std::array<double, 2>>& reference) {
  double err = 0.0, w[2];
  for (std::size_t k = 0; k < start.size(); ++k) {
    u.evaluate(start[k].data(), w);
    err = std::max(err, std::hypot(start[k][0] + w[0] - reference[k][0],
                                   start[k][1] + w[1] - reference[k][1]));
  }
  return err;
}

}  // namespace

TEST_CASE("scaling and squaring converges and its inverse is the identity", "[geometry][flow]") {
  const BumpVelocity velocity;
  std::vector<std::array<double, 2>> start, reference;
  core::RandomStream pts(22, core::Purpose::test, {});
  double max_disp = 0.0;
  for (int k = 0; k < 200; ++k) {
    start.push_back({-0.5 + pts.uniform(), -0.5 + pts.uniform()});
    reference.push_back(velocity.flow(start.back()));
    max_disp = std::max(max_disp, std::hypot(reference[k][0] - start[k][0], reference[k][1] - start[k][1]));
  }
  REQUIRE(max_disp > 0.15);  // a real deformation, not a near-identity

  // Time discretisation: with the grid fixed, the error falls with the number of squarings
  // until it reaches the interpolation floor (second-order first step: 4x per squaring).
  const GridField v_fine = velocity.on_grid(velocity.sigma / 16);
  std::vector<double> by_squarings;
  for (int n_sq : {0, 1, 2, 3, 8}) by_squarings.push_back(flow_error(geometry::exponentiate(v_fine, n_sq), start, reference));
  INFO("error vs RK4 for 0, 1, 2, 3, 8 squarings (spacing sigma/16): "
       << by_squarings[0] << " " << by_squarings[1] << " " << by_squarings[2] << " "
       << by_squarings[3] << " " << by_squarings[4] << "; max |u| " << max_disp);
  CHECK(by_squarings[1] < by_squarings[0] / 3);
  CHECK(by_squarings[2] < by_squarings[1] / 3);
  CHECK(by_squarings[3] < by_squarings[2] / 3);
  CHECK(by_squarings[4] < 1e-4 * max_disp);

  // Space discretisation: at the default number of squarings the error falls with the grid
  // spacing (Catmull-Rom interpolation of the displacement, third order).
  std::vector<double> by_spacing;
  for (double q : {4.0, 8.0, 16.0}) {
    const GridField v = velocity.on_grid(velocity.sigma / q);
    by_spacing.push_back(flow_error(geometry::exponentiate(v, geometry::default_squarings(v)), start, reference));
  }
  INFO("error vs RK4 for 4, 8, 16 nodes per sigma: " << by_spacing[0] << " " << by_spacing[1]
                                                    << " " << by_spacing[2]);
  CHECK(by_spacing[0] < 5e-3 * max_disp);  // the default resolution
  CHECK(by_spacing[1] < by_spacing[0] / 4);
  CHECK(by_spacing[2] < by_spacing[1] / 4);

  // exp(-v) o exp(v) = identity, on a GRF sample; the error converges with the grid spacing.
  std::vector<double> inverse_errors;
  double moved = 0.0;
  for (double q : {4.0, 6.0, 8.0}) {
    const Grid g = square_grid(2, 2.0, 0.2 / q);
    core::RandomStream rng(21, core::Purpose::test, {});
    const GridField v = geometry::sample_velocity_field(g, 0.2, 0.1, rng);
    GridField minus_v(g);
    for (int c = 0; c < 2; ++c)
      for (std::int64_t i = 0; i < g.n_nodes(); ++i) minus_v.at(i, c) = -v.at(i, c);
    const int n_sq = geometry::default_squarings(v);
    const GridField up = geometry::exponentiate(v, n_sq), um = geometry::exponentiate(minus_v, n_sq);
    double err = 0.0;
    for (const auto& x : start) {
      double w[2], y[2], z[2];
      up.evaluate(x.data(), w);
      y[0] = x[0] + w[0], y[1] = x[1] + w[1];
      moved = std::max(moved, std::hypot(w[0], w[1]));
      um.evaluate(y, z);
      err = std::max(err, std::hypot(y[0] + z[0] - x[0], y[1] + z[1] - x[1]));
    }
    inverse_errors.push_back(err);
  }
  INFO("inverse composition error at 4, 6, 8 nodes per sigma: " << inverse_errors[0] << " "
       << inverse_errors[1] << " " << inverse_errors[2] << " for max |u| " << moved);
  CHECK(moved > 0.1);
  CHECK(inverse_errors[1] < 2e-2 * moved);  // the 2D default
  CHECK(inverse_errors[2] < inverse_errors[0] / 8);
}

namespace {

/// The Catmull-Rom sum written out plainly, one component at a time over the 4^dim nodes in the
/// order (z, y, x), w = (w_z w_y) w_x: the arithmetic evaluate() must do, lane by lane.
void reference_evaluate(const GridField& f, const double* x, double* out) {
  const Grid& g = f.grid();
  int ix[3][4];
  double wx[3][4];
  for (int a = 0; a < 3; ++a) {
    if (g.n[a] == 1) {
      for (int q = 0; q < 4; ++q) ix[a][q] = 0, wx[a][q] = q == 1 ? 1.0 : 0.0;
      continue;
    }
    const double s = std::clamp((x[a] - g.lower[a]) / g.spacing, 0.0, double(g.n[a] - 1));
    const int i = std::min(int(s), g.n[a] - 2);
    const double t = s - i, t2 = t * t, t3 = t2 * t;
    wx[a][0] = 0.5 * (-t3 + 2.0 * t2 - t);
    wx[a][1] = 0.5 * (3.0 * t3 - 5.0 * t2 + 2.0);
    wx[a][2] = 0.5 * (-3.0 * t3 + 4.0 * t2 + t);
    wx[a][3] = 0.5 * (t3 - t2);
    for (int q = 0; q < 4; ++q) ix[a][q] = std::clamp(i - 1 + q, 0, g.n[a] - 1);
  }
  for (int d = 0; d < g.dim; ++d) {
    double acc = 0.0;
    for (int c = 0; c < (g.dim == 3 ? 4 : 1); ++c)
      for (int b = 0; b < 4; ++b) {
        const double wyz = (g.dim == 3 ? wx[2][c] : 1.0) * wx[1][b];
        for (int a = 0; a < 4; ++a) {
          const std::int64_t node = ix[0][a] + std::int64_t(g.n[0]) * (ix[1][b] + std::int64_t(g.n[1]) * ix[2][c]);
          acc += (wyz * wx[0][a]) * f.at(node, d);
        }
      }
    out[d] = acc;
  }
}

}  // namespace

TEST_CASE("evaluation at many points is the plain Catmull-Rom sum to the bit", "[geometry][grf]") {
  for (int dim : {2, 3}) {
    const Grid g = square_grid(dim, 1.0, 0.1);
    core::RandomStream rng(11, core::Purpose::test, {std::uint64_t(dim)});
    const GridField v = geometry::sample_velocity_field(g, 0.3, 1.0, rng);
    // 4k + 3 points (the fours and the tail), inside, near and beyond the grid's faces.
    const std::size_t n = 103;
    std::vector<double> x(n * std::size_t(dim)), many(x.size()), one(static_cast<std::size_t>(dim)), ref(one);
    for (double& c : x) c = -1.4 + 2.8 * rng.uniform();
    v.evaluate(n, x.data(), many.data());
    int differ = 0;
    for (std::size_t p = 0; p < n; ++p) {
      v.evaluate(&x[p * std::size_t(dim)], one.data());
      reference_evaluate(v, &x[p * std::size_t(dim)], ref.data());
      for (int d = 0; d < dim; ++d) {
        const double m = many[p * std::size_t(dim) + std::size_t(d)];
        differ += std::memcmp(&m, &one[std::size_t(d)], sizeof m) != 0;
        differ += std::memcmp(&m, &ref[std::size_t(d)], sizeof m) != 0;
      }
    }
    INFO("dim " << dim);
    CHECK(differ == 0);
  }
}
