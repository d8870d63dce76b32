#include "theory/HertzRange.hpp"

#include <cmath>

namespace trueaniso {

Real hertzOverlapRatio(const Material& m, Real pressure, Real solidFraction, Real coordination) {
  m.validate();
  require(std::isfinite(pressure) && pressure >= 0, "pressure must be a finite number >= 0");
  require(solidFraction > 0 && solidFraction < 1, "solid fraction must lie in (0, 1)");
  require(std::isfinite(coordination) && coordination > 0, "coordination number must be > 0");
  constexpr Real kPi = 3.14159265358979323846;
  const Real x = 3.0 * std::sqrt(2.0) * kPi * pressure / (solidFraction * coordination * m.contactModulus());
  return std::cbrt(x * x);  // x^(2/3)
}

}  // namespace trueaniso
