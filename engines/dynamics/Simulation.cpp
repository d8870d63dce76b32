#include "dynamics/Simulation.hpp"

namespace trueaniso {

Simulation::Simulation(std::shared_ptr<Scene> scene) : scene_(std::move(scene)) {
  require(scene_ != nullptr, "Simulation needs a scene");
}

long Simulation::run(long n) {
  require(n >= 0, "number of steps must be >= 0");
  scene_->validate();
  for (auto& e : engines_) e->done = false;
  long steps = 0;
  const auto runs = [&](const Engine& e) { return !e.dead && (e.every <= 1 || scene_->step % e.every == 0); };
  while (steps < n) {
    bool stop = false;
    bool measures = false;
    for (auto& e : engines_) measures = measures || (runs(*e) && e->readsCellMeasures());
    scene_->measured.wanted = measures;
    for (auto& e : engines_) {
      if (!runs(*e)) continue;
      e->apply(*scene_);
      ++e->applied;
      stop = stop || e->done;
    }
    scene_->time += scene_->dt;
    ++scene_->step;
    ++steps;
    if (stop) break;
  }
  return steps;
}

}  // namespace trueaniso
