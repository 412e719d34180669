// grid_points: the node set and its ordering (numpy 'ij' indexing, C order, x slowest).
#include <catch2/catch.hpp>
#include <cstddef>
#include <stdexcept>
#include <vector>

#include "hypershape/sampling/grid.hpp"

namespace hs = hypershape::sampling;

TEST_CASE("grid_points in 2D: 'ij' order, exact ends, symmetric", "[sampling][grid]") {
  const int n = 5;
  const std::vector<double> x = hs::grid_points(2, n);
  REQUIRE(x.size() == std::size_t(n * n * 2));
  const std::vector<double> axis = {-1.0, -0.5, 0.0, 0.5, 1.0};
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const std::size_t p = std::size_t(i * n + j);
      CHECK(x[2 * p] == axis[std::size_t(i)]);  // x index slowest
      CHECK(x[2 * p + 1] == axis[std::size_t(j)]);
    }
  // Odd spacing: ends exact, symmetric about 0.
  const int m = 128;
  const std::vector<double> y = hs::grid_points(2, m);
  CHECK(y[0] == -1.0);
  CHECK(y[1] == -1.0);
  CHECK(y.back() == 1.0);
  for (int i = 0; i < m; ++i) {
    const double a = y[std::size_t(2 * i * m)], b = y[std::size_t(2 * (m - 1 - i) * m)];
    CHECK(a == -b);
    CHECK(a == Approx(-1.0 + 2.0 * i / (m - 1)).margin(1e-15));
  }
}

TEST_CASE("grid_points in 3D: flat index (i * n + j) * n + k", "[sampling][grid]") {
  const int n = 4;
  const std::vector<double> x = hs::grid_points(3, n);
  REQUIRE(x.size() == std::size_t(n * n * n * 3));
  const auto c = [&](int i) { return -1.0 + 2.0 * i / (n - 1); };
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) {
        const std::size_t p = std::size_t((i * n + j) * n + k);
        CHECK(x[3 * p] == Approx(c(i)).margin(1e-15));
        CHECK(x[3 * p + 1] == Approx(c(j)).margin(1e-15));
        CHECK(x[3 * p + 2] == Approx(c(k)).margin(1e-15));
      }
  const std::vector<double> two = hs::grid_points(3, 2);  // the 8 corners
  CHECK(two == std::vector<double>{-1, -1, -1, -1, -1, 1, -1, 1, -1, -1, 1, 1,
                                   1,  -1, -1, 1,  -1, 1, 1,  1, -1, 1,  1, 1});
}

TEST_CASE("grid_points rejects bad arguments", "[sampling][grid]") {
  CHECK_THROWS_AS(hs::grid_points(2, 1), std::invalid_argument);
  CHECK_THROWS_AS(hs::grid_points(3, 0), std::invalid_argument);
  CHECK_THROWS_AS(hs::grid_points(1, 8), std::invalid_argument);
  CHECK_THROWS_AS(hs::grid_points(4, 8), std::invalid_argument);
}
