#pragma once
// Periodic orthorhombic cell. Its three diagonal strain rates are the control variables of
// the servo and probe engines; an off-diagonal cell is not needed by any path of the study.
#include "core/Types.hpp"

namespace trueaniso {

struct Cell {
  Vec3 size = Vec3::Ones();           // h_x, h_y, h_z (m)
  Vec3 refSize = Vec3::Ones();        // size at which strain is zero
  Vec3 strainRate = Vec3::Zero();     // d ln(h_k)/dt, positive = extension

  Real volume() const { return size.prod(); }
  // Logarithmic strain, compression positive (the geomechanics sign convention used for stress).
  Vec3 strain() const {
    return Vec3(-std::log(size.x() / refSize.x()), -std::log(size.y() / refSize.y()),
                -std::log(size.z() / refSize.z()));
  }
  // Image displacement of a periodic shift (integer cell vector).
  Vec3 shiftVector(const Vec3i& s) const { return s.cast<Real>().cwiseProduct(size); }
};

}  // namespace trueaniso
