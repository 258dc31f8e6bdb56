// SPDX-License-Identifier: BSD-3-Clause
// core/include/penumbra/core/vec3.h
#pragma once
#include <cmath>

#include "penumbra/core/export.h"

PNB_PUBLIC_BEGIN

namespace penumbra {

/// Small fixed-size 3-vector used for geometry in double and float precision.
template <class T>
struct Vec3 {
  T x{}, y{}, z{};
  constexpr T& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
  constexpr T operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
  constexpr bool operator==(const Vec3&) const = default;
};
template <class T> constexpr Vec3<T> operator+(Vec3<T> a, Vec3<T> b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
template <class T> constexpr Vec3<T> operator-(Vec3<T> a, Vec3<T> b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
template <class T> constexpr Vec3<T> operator-(Vec3<T> a) { return {-a.x, -a.y, -a.z}; }
template <class T> constexpr Vec3<T> operator*(Vec3<T> a, T s) { return {a.x * s, a.y * s, a.z * s}; }
template <class T> constexpr Vec3<T> operator*(T s, Vec3<T> a) { return {a.x * s, a.y * s, a.z * s}; }
template <class T> constexpr Vec3<T> operator/(Vec3<T> a, T s) { return {a.x / s, a.y / s, a.z / s}; }
template <class T> constexpr T dot(Vec3<T> a, Vec3<T> b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
template <class T> constexpr Vec3<T> cross(Vec3<T> a, Vec3<T> b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
template <class T> inline T length(Vec3<T> a) { return std::sqrt(dot(a, a)); }
template <class T> inline Vec3<T> normalize(Vec3<T> a) { return a / length(a); }
template <class T> constexpr Vec3<T> min(Vec3<T> a, Vec3<T> b) {
  return {a.x < b.x ? a.x : b.x, a.y < b.y ? a.y : b.y, a.z < b.z ? a.z : b.z};
}
template <class T> constexpr Vec3<T> max(Vec3<T> a, Vec3<T> b) {
  return {a.x > b.x ? a.x : b.x, a.y > b.y ? a.y : b.y, a.z > b.z ? a.z : b.z};
}

using Vec3d = Vec3<double>;
using Vec3f = Vec3<float>;

/// Signed volume of tet (a,b,c,d) times 6: positive when d lies on the side of (a,b,c) that
/// its right-handed normal points to (VTK's tetra orientation).
inline double signed_volume6(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& d) {
  return dot(cross(b - a, c - a), d - a);
}

/// Axis-aligned bounding box; empty when lo > hi.
struct Bounds {
  Vec3d lo{1e300, 1e300, 1e300};
  Vec3d hi{-1e300, -1e300, -1e300};
  void extend(const Vec3d& p) { lo = min(lo, p); hi = max(hi, p); }
  bool empty() const { return lo.x > hi.x; }
  Vec3d center() const { return (lo + hi) * 0.5; }
  double diagonal() const { return empty() ? 0.0 : length(hi - lo); }
};

}  // namespace penumbra

PNB_PUBLIC_END
