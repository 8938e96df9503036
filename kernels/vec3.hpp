// The 3-vector the kernels are written on: Eigen's Vector3d in double (what the models use), or Vec3<T>, whose
// every operation is written out so that its order is fixed (dot(a, b) = (a.x b.x + a.y b.y) + a.z b.z,
// |a| = sqrt(dot(a, a))): what a shader computes node by node in float32 and its CPU reference.
// A kernel calls dot, norm and cross unqualified, so one text serves both.
#pragma once

#include <Eigen/Dense>

#include <cmath>
#include <utility>

namespace stepwise {

template <class T>
struct Vec3 {
  T x = 0, y = 0, z = 0;
};
template <class T>
Vec3<T> operator+(Vec3<T> a, Vec3<T> b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
template <class T>
Vec3<T> operator-(Vec3<T> a, Vec3<T> b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
template <class T>
Vec3<T> operator*(T s, Vec3<T> a) { return {s * a.x, s * a.y, s * a.z}; }
template <class T>
Vec3<T> operator/(Vec3<T> a, T s) { return {a.x / s, a.y / s, a.z / s}; }
template <class T>
T dot(Vec3<T> a, Vec3<T> b) { return (a.x * b.x + a.y * b.y) + a.z * b.z; }
template <class T>
T norm(Vec3<T> a) { return std::sqrt(dot(a, a)); }
template <class T>
Vec3<T> cross(Vec3<T> a, Vec3<T> b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
template <class T>
Vec3<T> vec3(const Eigen::Vector3d& v) { return {static_cast<T>(v.x()), static_cast<T>(v.y()), static_cast<T>(v.z())}; }

inline double dot(const Eigen::Vector3d& a, const Eigen::Vector3d& b) { return a.dot(b); }
inline double norm(const Eigen::Vector3d& a) { return a.norm(); }
inline Eigen::Vector3d cross(const Eigen::Vector3d& a, const Eigen::Vector3d& b) { return a.cross(b); }

// the scalar of a vector type: double for Eigen::Vector3d, T for Vec3<T>
template <class V>
using Scalar = decltype(dot(std::declval<V>(), std::declval<V>()));

}  // namespace stepwise
