// Environment map radiance and importance sampling (environment.hpp).
#include "render/environment.hpp"

#include <algorithm>
#include <cmath>

namespace clothbake::render {
namespace {

constexpr double kPi = 3.14159265358979323846;

double luminance(const float* rgb) {
  return 0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2];
}

// Solid angle of row y's pixels.
double pixel_solid_angle(int y, int width, int height) {
  const double t0 = kPi * y / height, t1 = kPi * (y + 1) / height;
  return (2.0 * kPi / width) * (std::cos(t0) - std::cos(t1));
}

}  // namespace

Environment::Environment(const EnvironmentMap& map) : map_(&map) {
  const int w = map.width, h = map.height;
  weight_.assign(std::size_t(w) * h, 0.0);
  column_cdf_.assign(std::size_t(h) * (w + 1), 0.0);
  row_cdf_.assign(std::size_t(h) + 1, 0.0);
  double total = 0;
  for (int y = 0; y < h; ++y) {
    const double omega = pixel_solid_angle(y, w, h);
    double row = 0;
    for (int x = 0; x < w; ++x) {
      const double v = std::max(0.0, luminance(&map.rgb[(std::size_t(y) * w + x) * 3])) * omega;
      weight_[std::size_t(y) * w + x] = v;
      row += v;
      column_cdf_[std::size_t(y) * (w + 1) + x + 1] = row;
    }
    total += row;
    row_cdf_[y + 1] = total;
  }
  if (!(total > 0)) return;  // a black map: never sampled (pdf 0 everywhere)
  for (double& v : weight_)
    v /= total;
  for (double& v : row_cdf_)
    v /= total;
  for (int y = 0; y < h; ++y) {
    double* c = &column_cdf_[std::size_t(y) * (w + 1)];
    if (c[w] > 0)
      for (int x = 1; x <= w; ++x)
        c[x] /= c[w];
  }
}

int Environment::pixel_of(const Vec3& d) const {
  const int w = map_->width, h = map_->height;
  const double theta = std::acos(std::clamp(d.y, -1.0, 1.0));
  double phi = std::atan2(d.z, d.x);
  if (phi < 0) phi += 2 * kPi;
  const int x = std::min(w - 1, int(phi / (2 * kPi) * w));
  const int y = std::min(h - 1, int(theta / kPi * h));
  return y * w + x;
}

Rgb Environment::radiance(const Vec3& d) const {
  if (map_->width == 0) return {};
  const float* p = &map_->rgb[std::size_t(pixel_of(d)) * 3];
  return Rgb(p[0], p[1], p[2]) * map_->scale;
}

double Environment::pdf(const Vec3& d) const {
  if (map_->width == 0 || !(row_cdf_.back() > 0)) return 0;
  const int k = pixel_of(d);
  const double omega = pixel_solid_angle(k / map_->width, map_->width, map_->height);
  return weight_[std::size_t(k)] / omega;
}

Vec3 Environment::sample(double u1, double u2, double* pdf) const {
  const int w = map_->width, h = map_->height;
  *pdf = 0;
  if (w == 0 || !(row_cdf_.back() > 0)) return {0, 1, 0};
  // Row by the marginal CDF, then column by the row's conditional CDF (binary searches).
  const int y = std::clamp(
      int(std::upper_bound(row_cdf_.begin(), row_cdf_.end(), u1) - row_cdf_.begin()) - 1, 0, h - 1);
  const double* c = &column_cdf_[std::size_t(y) * (w + 1)];
  const double* hit = std::upper_bound(c, c + w + 1, u2);
  const int x = std::clamp(int(hit - c) - 1, 0, w - 1);
  // Reuse the fractional positions inside the chosen bins as uniform numbers.
  const double row_width = row_cdf_[y + 1] - row_cdf_[y];
  const double fy = row_width > 0 ? (u1 - row_cdf_[y]) / row_width : 0.5;
  const double col_width = c[x + 1] - c[x];
  const double fx = col_width > 0 ? (u2 - c[x]) / col_width : 0.5;
  const double phi = 2 * kPi * (x + std::clamp(fx, 0.0, 1.0)) / w;
  const double c0 = std::cos(kPi * y / h), c1 = std::cos(kPi * (y + 1) / h);
  const double cos_theta = c0 + (c1 - c0) * std::clamp(fy, 0.0, 1.0);
  const double sin_theta = std::sqrt(std::max(0.0, 1 - cos_theta * cos_theta));
  const Vec3 d{sin_theta * std::cos(phi), cos_theta, sin_theta * std::sin(phi)};
  *pdf = weight_[std::size_t(y) * w + x] / pixel_solid_angle(y, w, h);
  return d;
}

}  // namespace clothbake::render
