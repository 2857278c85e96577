// Half-vector bins, their quadrature and the 2-sigma rule (half_vector_bins.hpp).
#include "tables/half_vector_bins.hpp"

#include <algorithm>
#include <cmath>

#include "common/error.hpp"
#include "model/directions.hpp"

namespace clothbake::tables {

HalfVectorBins make_half_vector_bins(int bins_per_side, int samples_per_side) {
  if (bins_per_side < 1 || bins_per_side > kMaxBinsPerSide)
    throw_input_error("radiance_dirs = " + std::to_string(bins_per_side) + " is outside [1, " +
                      std::to_string(kMaxBinsPerSide) + "]");
  if (samples_per_side < 1 || samples_per_side > kMaxSamplesPerBinSide)
    throw_input_error("samples per bin side = " + std::to_string(samples_per_side) +
                      " is outside [1, " + std::to_string(kMaxSamplesPerBinSide) + "]");
  const int n = bins_per_side, s = samples_per_side;
  const model::DirectionGrid<double> grid{n, 0.0};
  HalfVectorBins out;
  out.bins_per_side = n;
  out.samples_per_side = s;
  const std::size_t total = std::size_t(n) * std::size_t(n) * std::size_t(s) * std::size_t(s);
  out.x.reserve(total);
  out.y.reserve(total);
  out.z.reserve(total);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      for (int q = 0; q < s; ++q)
        for (int p = 0; p < s; ++p) {
          const double u = (double(i) + (double(p) + 0.5) / double(s)) / double(n);
          const double v = (double(j) + (double(q) + 0.5) / double(s)) / double(n);
          const model::Vec3d d = grid.direction(u, v);
          out.x.push_back(float(d.x));
          out.y.push_back(float(d.y));
          out.z.push_back(float(d.z));
        }
  return out;
}

double bin_angular_width(int bins_per_side) {
  return std::sqrt(2.0 * model::kPi<double>) / double(std::max(bins_per_side, 1));
}

int bins_per_side_for_roughness(double sigma) {
  if (!(sigma > 0.0)) return kMaxBinsPerSide;
  const double n = std::ceil(std::sqrt(2.0 * model::kPi<double>) / (2.0 * sigma) - 1e-9);
  return int(std::clamp(n, 1.0, 1e9));
}

bool bins_resolve_roughness(int bins_per_side, double sigma) {
  return bin_angular_width(bins_per_side) <= 2.0 * sigma * (1.0 + 1e-9);
}

int default_bins_per_side(double min_roughness) {
  if (!(min_roughness > 0.0)) return 128;
  const double n = std::ceil(3.0 * std::sqrt(2.0 * model::kPi<double>) / min_roughness - 1e-9);
  return int(std::clamp(n, 32.0, 128.0));
}

int default_samples_per_side(int bins_per_side, double min_roughness) {
  if (!(min_roughness > 0.0)) return 8;
  const double s = std::ceil(bin_angular_width(bins_per_side) / (0.5 * min_roughness) - 1e-9);
  return int(std::clamp(s, 2.0, 8.0));
}

}  // namespace clothbake::tables
