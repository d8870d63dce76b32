#pragma once
// What a cell controller reads each step. Measured on our scene by the engines, or on YADE's O by
// the YADE adapter, so one control logic drives both.
#include "core/Scene.hpp"

namespace trueaniso {

struct CellMeasurement {
  Vec6 stress = Vec6::Zero();        // Love-Weber stress (symmetric part, Voigt), compression positive
  // The cell's deformation gradient since its reference: a controller takes its strains between
  // two of these (strainBetween), so a flip of the cell between them changes nothing.
  Mat3 deformation = Mat3::Identity();
  Vec6 stiffness = Vec6::Zero();     // affine stiffness per Voigt component (Pa per unit strain)
  Real unbalanced = 0;               // YADE's unbalanced force

  // From the force loop's sums of this step when it made them (an engine that reads this says so,
  // Engine::readsCellMeasures), else from a pass over the contacts: the same bits (measure/Stress.hpp).
  static CellMeasurement of(const Scene& scene);
};

}  // namespace trueaniso
