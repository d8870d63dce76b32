#pragma once
// The ABI self-test's engine (engines/yade/selftest.py): what it reads of the scene must be what
// Python reads. Included by TrueanisoYade.cpp.
#include <core/GlobalEngine.hpp>
#include <core/Scene.hpp>

namespace yade {

class TrueanisoAbiCheck : public GlobalEngine {
 public:
  void action() override {
    iters.push_back(static_cast<Real>(scene->iter));
    times.push_back(scene->time);
    dts.push_back(scene->dt);
    cellVolumes.push_back(scene->isPeriodic ? scene->cell->hSize.determinant() : 0.0);
    bodyCount = static_cast<int>(scene->bodies->size());
  }
  // clang-format off
  YADE_CLASS_BASE_DOC_ATTRS(TrueanisoAbiCheck, GlobalEngine,
    "Records scene->iter, time, dt and the cell volume every step: the build's self-test compares them with "
    "O.iter, O.time, O.dt and O.cell.volume read from Python.",
    ((vector<Real>, iters, , Attr::readonly, "scene->iter at each call"))
    ((vector<Real>, times, , Attr::readonly, "scene->time at each call"))
    ((vector<Real>, dts, , Attr::readonly, "scene->dt at each call"))
    ((vector<Real>, cellVolumes, , Attr::readonly, "det(hSize) at each call"))
    ((int, bodyCount, 0, Attr::readonly, "scene->bodies->size()")));
  // clang-format on
};
REGISTER_SERIALIZABLE(TrueanisoAbiCheck);

}  // namespace yade
