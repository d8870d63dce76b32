#pragma once
// An ordered list of engines acting on one scene.
#include <memory>
#include <vector>

#include "core/Engine.hpp"

namespace trueaniso {

class Simulation {
 public:
  explicit Simulation(std::shared_ptr<Scene> scene);
  void add(std::shared_ptr<Engine> e) { engines_.push_back(std::move(e)); }
  void clear() { engines_.clear(); }
  const std::vector<std::shared_ptr<Engine>>& engines() const { return engines_; }
  // Runs n steps. Returns the steps done: fewer than n when an engine set `done`.
  long run(long n);
  Scene& scene() { return *scene_; }
  std::shared_ptr<Scene> scenePtr() { return scene_; }

 private:
  std::shared_ptr<Scene> scene_;
  std::vector<std::shared_ptr<Engine>> engines_;
};

}  // namespace trueaniso
