#pragma once
/// Statistics of measured samples, for the benchmarks and the accuracy study: one median, one
/// mean, one JSON number (non-finite values become null).
#include <cmath>
#include <nlohmann/json.hpp>
#include <vector>

namespace hypershape::study {

/// Median of the finite values of `v` (the mean of the two middle ones for an even count);
/// NaN when there is none. Not collective.
double median(std::vector<double> v);

/// Mean of the finite values of `v`; NaN when there is none. Not collective.
double finite_mean(const std::vector<double>& v);

/// `v` as a JSON number, or null when it is not finite (JSON has no NaN or infinity).
inline nlohmann::json number_or_null(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

/// `v` as a JSON array of number_or_null values.
nlohmann::json numbers_or_null(const std::vector<double>& v);

}  // namespace hypershape::study
