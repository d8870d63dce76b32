#pragma once
// What a cell controller reads each step. Measured on our scene by the engines, or on YADE's O by
// the YADE adapter, so one control logic drives both.
#include "core/Scene.hpp"

namespace trueaniso {

struct CellMeasurement {
  Vec3 stress = Vec3::Zero();     // diagonal of the Love-Weber stress, compression positive
  Vec3 strain = Vec3::Zero();     // logarithmic cell strain, compression positive
  Vec3 stiffness = Vec3::Zero();  // affine axial stiffness estimate (Pa per unit strain)
  Real unbalanced = 0;            // YADE's unbalanced force

  static CellMeasurement of(const Scene& scene);
};

}  // namespace trueaniso
