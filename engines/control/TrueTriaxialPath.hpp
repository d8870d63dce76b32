#pragma once
// Stress paths of constant b and constant mean stress p (paper Eqs. 8-9).
#include <cmath>
#include <sstream>

#include "core/Types.hpp"

namespace trueaniso {

struct TrueTriaxialState {
  Real b = 0;         // intermediate principal stress coefficient, Eq. (8)
  Real sigmaZ = 100e3;
  Real p = 100e3;     // mean stress, held constant along the path

  // Eq. (9): sigma_x and sigma_y that keep b and p with the given sigma_z.
  Vec3 stresses() const {
    const Real sx = ((2 * b - 1) * sigmaZ + 3 * p * (1 - b)) / (2 - b);
    const Real sy = (3 * p - (b + 1) * sigmaZ) / (2 - b);
    return Vec3(sx, sy, sigmaZ);
  }
  // Eq. (13): signed deviatoric stress, the sign of sigma_z - sigma_y.
  Real q() const {
    const Vec3 s = stresses();
    const Real v = std::sqrt(0.5 * ((s.z() - s.x()) * (s.z() - s.x()) + (s.x() - s.y()) * (s.x() - s.y()) +
                                    (s.y() - s.z()) * (s.y() - s.z())));
    return s.z() >= s.y() ? v : -v;
  }
  void validate() const {
    std::ostringstream m;
    if (!(b >= 0 && b <= 1)) m << "b = " << b << " is outside [0, 1]";
    else if (!(p > 0)) m << "mean stress p = " << p << " Pa must be > 0";
    // inf gave "principal stresses (-nan, -inf, inf)": the input named, not what follows from it
    else if (!std::isfinite(sigmaZ) || !std::isfinite(p))
      m << "sigma_z = " << sigmaZ << " Pa and p = " << p << " Pa must be finite";
    else {
      const Vec3 s = stresses();
      if (!((s.array() > 0).all()))
        m << "sigma_z = " << sigmaZ << " Pa with b = " << b << " and p = " << p
          << " Pa gives principal stresses (" << s.x() << ", " << s.y() << ", " << s.z()
          << ") Pa: every one must be > 0";
    }
    if (!m.str().empty()) throw InputError(m.str());
  }
};

// Eq. (12): the probe's shear strain measure from the three strain increments.
inline Real shearStrainGamma(const Vec3& de) {
  return std::sqrt(0.5 * ((de.x() - de.y()) * (de.x() - de.y()) + (de.x() - de.z()) * (de.x() - de.z()) +
                          (de.y() - de.z()) * (de.y() - de.z())));
}

}  // namespace trueaniso
