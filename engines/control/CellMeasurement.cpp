#include "control/CellMeasurement.hpp"

#include "measure/Stress.hpp"

namespace trueaniso {

CellMeasurement CellMeasurement::of(const Scene& s) {
  const ContactMeasures c = cellMeasures(s);
  CellMeasurement m;
  m.stress = voigt::fromTensor(c.stress);
  m.deformation = s.cell.deformation();
  m.stiffness = c.stiffness;
  m.unbalanced = c.unbalanced;
  return m;
}

}  // namespace trueaniso
