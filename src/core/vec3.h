// The one 3-vector of RayPC: positions in km, directions, velocities. Vec3d for geometry and
// integration (data/), Vec3f for the renderer's per-sample work (render::Vec3).
#pragma once

#include <cmath>
#include <type_traits>

namespace raypc {

template <class T>
struct Vec3T {
    T x = 0, y = 0, z = 0;
};
using Vec3d = Vec3T<double>;
using Vec3f = Vec3T<float>;

// The scalar parameters are not deduced, so `v * 0.5` works for both precisions.
template <class T>
constexpr Vec3T<T> operator+(Vec3T<T> a, Vec3T<T> b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
template <class T>
constexpr Vec3T<T> operator-(Vec3T<T> a, Vec3T<T> b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
template <class T>
constexpr Vec3T<T> operator-(Vec3T<T> a) { return {-a.x, -a.y, -a.z}; }
template <class T>
constexpr Vec3T<T> operator*(Vec3T<T> a, std::type_identity_t<T> s) { return {a.x * s, a.y * s, a.z * s}; }
template <class T>
constexpr Vec3T<T> operator*(std::type_identity_t<T> s, Vec3T<T> a) { return {s * a.x, s * a.y, s * a.z}; }
template <class T>
constexpr T dot(Vec3T<T> a, Vec3T<T> b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
template <class T>
constexpr Vec3T<T> cross(Vec3T<T> a, Vec3T<T> b)
{
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
template <class T>
T length(Vec3T<T> a) { return std::sqrt(dot(a, a)); }
// a / |a|; not finite for the zero vector.
template <class T>
Vec3T<T> normalize(Vec3T<T> a) { return a * (T(1) / length(a)); }

}  // namespace raypc
