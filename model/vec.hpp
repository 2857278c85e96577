// Minimal 3-vector for the dependency-free model library (C++17, header-only, float or double).
#pragma once

#include <cmath>

namespace clothbake::model {

template <class T>
struct Vec3 {
  T x{}, y{}, z{};
  constexpr Vec3() = default;
  constexpr Vec3(T x_, T y_, T z_) : x(x_), y(y_), z(z_) {}
  template <class U>
  constexpr explicit Vec3(const Vec3<U>& v) : x(T(v.x)), y(T(v.y)), z(T(v.z)) {}
  constexpr T operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
  constexpr Vec3 operator+(const Vec3& o) const { return {x + o.x, y + o.y, z + o.z}; }
  constexpr Vec3 operator-(const Vec3& o) const { return {x - o.x, y - o.y, z - o.z}; }
  constexpr Vec3 operator-() const { return {-x, -y, -z}; }
  constexpr Vec3 operator*(T s) const { return {x * s, y * s, z * s}; }
  constexpr Vec3 operator/(T s) const { return {x / s, y / s, z / s}; }
  constexpr Vec3& operator+=(const Vec3& o) {
    x += o.x;
    y += o.y;
    z += o.z;
    return *this;
  }
  constexpr Vec3& operator-=(const Vec3& o) {
    x -= o.x;
    y -= o.y;
    z -= o.z;
    return *this;
  }
  constexpr Vec3& operator*=(T s) {
    x *= s;
    y *= s;
    z *= s;
    return *this;
  }
};

template <class T>
constexpr Vec3<T> operator*(T s, const Vec3<T>& v) {
  return v * s;
}
template <class T>
constexpr T dot(const Vec3<T>& a, const Vec3<T>& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
template <class T>
constexpr Vec3<T> cross(const Vec3<T>& a, const Vec3<T>& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
template <class T>
inline T length(const Vec3<T>& v) {
  return std::sqrt(dot(v, v));
}
// Returns v / |v|; the zero vector stays zero (callers that cannot accept it check first).
template <class T>
inline Vec3<T> normalize(const Vec3<T>& v) {
  T len = length(v);
  return len > T(0) ? v / len : v;
}

// An orthonormal basis (s, t, n) around unit n (Duff et al. 2017, "Building an Orthonormal Basis,
// Revisited"): continuous except at n.z = -1's sign flip, no division by a small number.
template <class T>
inline void orthonormal_basis(const Vec3<T>& n, Vec3<T>& s, Vec3<T>& t) {
  T sign = std::copysign(T(1), n.z);
  T a = T(-1) / (sign + n.z);
  T b = n.x * n.y * a;
  s = {T(1) + sign * n.x * n.x * a, sign * b, -sign * n.x};
  t = {b, sign + n.y * n.y * a, -n.y};
}

using Vec3f = Vec3<float>;
using Vec3d = Vec3<double>;

}  // namespace clothbake::model
