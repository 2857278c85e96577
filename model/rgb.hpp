// Linear RGB triple for the albedos and lobe values of the cloth BSDF (C++17, header-only, float or
// double). Component-wise arithmetic only; no colour-space conversion anywhere in the model.
#pragma once

#include <algorithm>

namespace clothbake::model {

template <class T>
struct Rgb {
  T r{}, g{}, b{};
  constexpr Rgb() = default;
  constexpr Rgb(T r_, T g_, T b_) : r(r_), g(g_), b(b_) {}
  constexpr explicit Rgb(T v) : r(v), g(v), b(v) {}
  template <class U>
  constexpr explicit Rgb(const Rgb<U>& c) : r(T(c.r)), g(T(c.g)), b(T(c.b)) {}

  constexpr T operator[](int i) const { return i == 0 ? r : (i == 1 ? g : b); }
  constexpr Rgb operator+(const Rgb& o) const { return {r + o.r, g + o.g, b + o.b}; }
  constexpr Rgb operator-(const Rgb& o) const { return {r - o.r, g - o.g, b - o.b}; }
  constexpr Rgb operator*(const Rgb& o) const { return {r * o.r, g * o.g, b * o.b}; }
  constexpr Rgb operator*(T s) const { return {r * s, g * s, b * s}; }
  constexpr Rgb operator/(T s) const { return {r / s, g / s, b / s}; }
  constexpr Rgb& operator+=(const Rgb& o) {
    r += o.r;
    g += o.g;
    b += o.b;
    return *this;
  }
  constexpr Rgb& operator*=(T s) {
    r *= s;
    g *= s;
    b *= s;
    return *this;
  }

  // Arithmetic mean of the channels: the scalar the lobe selection of the sampler uses
  // (docs/model.md).
  constexpr T mean() const { return (r + g + b) / T(3); }
  constexpr T max_component() const { return std::max(r, std::max(g, b)); }
  constexpr T min_component() const { return std::min(r, std::min(g, b)); }
};

template <class T>
constexpr Rgb<T> operator*(T s, const Rgb<T>& c) {
  return c * s;
}

}  // namespace clothbake::model
