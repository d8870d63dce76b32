#pragma once
// Records the fabric of the contact network every `every` steps into an in-memory history, as a
// YADE PyRunner recorder would, but without leaving C++. Put it after ContactForces in the
// engine list: it reads the contacts of the step's force evaluation.
#include <vector>

#include "core/Engine.hpp"
#include "measure/Fabric.hpp"

namespace trueaniso {

// One row per record, tensors flattened in C order: R, H, B as [i][j] (9 values), M as
// [i][j][k][l] (81 values), so Python reshapes them to (n, 3, 3) and (n, 3, 3, 3, 3).
struct FabricHistory {
  std::vector<long> step, contacts, particles, noContact, oneContact;
  std::vector<Real> time, Zm, contactDensityEq36, contactDensityCount, voidRatio, meanNormalForce,
      volume, meanRadiusCubed;
  std::vector<Real> R, H, B, M;

  int size() const { return static_cast<int>(step.size()); }
  void append(long step, Real time, const Fabric& f);
  void reserve(int rows);
  void clear() { *this = FabricHistory(); }
};

class FabricRecorder : public Engine {
 public:
  FabricRecorder() { every = 100; }
  void apply(Scene& scene) override;
  std::string name() const override { return "FabricRecorder"; }

  FabricHistory history;
  Fabric last;  // the latest record in full
};

}  // namespace trueaniso
