#include "control/CellMeasurement.hpp"

#include "measure/Stress.hpp"

namespace trueaniso {

CellMeasurement CellMeasurement::of(const Scene& s) {
  CellMeasurement m;
  m.stress = voigt::fromTensor(loveWeberStress(s));
  m.deformation = s.cell.deformation();
  m.stiffness = affineStiffness(s);
  m.unbalanced = unbalancedForce(s);
  return m;
}

}  // namespace trueaniso
