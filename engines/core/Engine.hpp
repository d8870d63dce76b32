#pragma once
// An engine acts on the scene once per step (or every `every` steps), in the order of the
// simulation's engine list, as in YADE's O.engines. It owns only its parameters and state.
#include <string>

#include "core/Scene.hpp"

namespace trueaniso {

class Engine {
 public:
  virtual ~Engine() = default;
  virtual void apply(Scene& scene) = 0;
  virtual std::string name() const = 0;
  // True for an engine that reads the cell measures (stress, affine stiffness, unbalanced force:
  // control/CellMeasurement.hpp) when it runs: in its steps the contact loop sums them while it
  // computes the forces (measure/CellSums.hpp), and in no other step.
  virtual bool readsCellMeasures() const { return false; }
  long every = 1;  // run at steps where step % every == 0
  bool dead = false;  // skipped when true (for example contact detection during a probe)
  // Times the simulation applied this engine: lets a protocol show that a switched-off engine
  // really did not run (a dead detection costs nothing, not even its rebuild check).
  long applied = 0;
  // Set by an engine that reached its goal (a servo at its target, a probe at gamma): the
  // simulation finishes the current step and returns. Cleared by the next run().
  bool done = false;
};

}  // namespace trueaniso
