#include "control/CellMeasurement.hpp"

#include "measure/Stress.hpp"

namespace trueaniso {

CellMeasurement CellMeasurement::of(const Scene& s) {
  CellMeasurement m;
  m.stress = loveWeberStress(s).diagonal();
  m.strain = s.cell.strain();
  m.stiffness = affineAxialStiffness(s);
  m.unbalanced = unbalancedForce(s);
  return m;
}

}  // namespace trueaniso
