#pragma once
// Basic numeric types. Everything is SI (m, kg, s, N, Pa) and double precision, as in yade-double.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <stdexcept>
#include <string>

namespace trueaniso {

using Real = double;
using Vec3 = Eigen::Vector3d;
using Vec3i = Eigen::Vector3i;
using Mat3 = Eigen::Matrix3d;
using Quat = Eigen::Quaterniond;
// Voigt 6x6 stiffness and 6-vectors, order xx, yy, zz, yz, xz, xy (Eq. 38; statics/Voigt.hpp).
using Mat6 = Eigen::Matrix<Real, 6, 6>;
using Vec6 = Eigen::Matrix<Real, 6, 1>;

// Thrown for bad input before any work starts; the Python layer turns it into one clear line.
struct InputError : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

inline void require(bool ok, const std::string& what) {
  if (!ok) throw InputError(what);
}

// q scaled to unit norm, but returned as it is when it is a unit quaternion to round-off already:
// normalising is not idempotent in the last bits, and a saved orientation must load bit for bit.
inline Quat unitQuaternion(const Quat& q) {
  const Real n2 = q.squaredNorm();
  return (n2 > 1.0 - 1e-14 && n2 < 1.0 + 1e-14) ? q : q.normalized();
}

}  // namespace trueaniso
