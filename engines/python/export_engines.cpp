// Engines and the simulation loop as seen from Python. Parameters are validated by the engines
// themselves when they run and by the Python layer before a run starts.
#include <memory>

#include "control/RadiusExpansion.hpp"
#include "control/StressServo.hpp"
#include "dynamics/ContactDetection.hpp"
#include "dynamics/ContactForces.hpp"
#include "dynamics/NewtonIntegrator.hpp"
#include "dynamics/Simulation.hpp"
#include "dynamics/TimeStepper.hpp"
#include "python/Numpy.hpp"

namespace trueaniso::py {

namespace {

template <class E, Vec3 E::*F>
np::ndarray getVec(const E& e) { return toNumpy(e.*F); }
template <class E, Vec3 E::*F>
void setVec(E& e, const bp::object& o) { e.*F = toVec3(o, "vector parameter"); }

bp::list engines(const Simulation& sim) {
  bp::list l;
  for (const auto& e : sim.engines()) l.append(e);
  return l;
}

long runSteps(Simulation& sim, long n) {
  // Long runs release the GIL so a Python thread (progress display, YADE's UI) stays alive.
  PyThreadState* state = PyEval_SaveThread();
  try {
    const long done = sim.run(n);
    PyEval_RestoreThread(state);
    return done;
  } catch (...) {
    PyEval_RestoreThread(state);
    throw;
  }
}

}  // namespace

void exportEngines() {
  bp::class_<Engine, std::shared_ptr<Engine>, boost::noncopyable>("Engine", bp::no_init)
      .def("apply", &Engine::apply)
      .add_property("name", &Engine::name)
      .def_readwrite("every", &Engine::every)
      .def_readwrite("dead", &Engine::dead)
      .def_readwrite("done", &Engine::done);

  bp::class_<ContactDetection, bp::bases<Engine>, std::shared_ptr<ContactDetection>>("ContactDetection")
      .def_readwrite("skin_factor", &ContactDetection::skinFactor)
      .def_readonly("rebuilds", &ContactDetection::rebuilds)
      .def_readonly("lost_contacts", &ContactDetection::lostContacts)
      .def("rebuild", &ContactDetection::rebuild)
      .def("needs_rebuild", &ContactDetection::needsRebuild);

  bp::class_<ContactForces, bp::bases<Engine>, std::shared_ptr<ContactForces>>("ContactForces")
      .def_readonly("sliding_contacts", &ContactForces::slidingContacts);

  bp::class_<NewtonIntegrator, bp::bases<Engine>, std::shared_ptr<NewtonIntegrator>>("NewtonIntegrator")
      .def_readwrite("damping", &NewtonIntegrator::damping)
      .def_readwrite("check_every", &NewtonIntegrator::checkEvery);

  bp::class_<TimeStepper, bp::bases<Engine>, std::shared_ptr<TimeStepper>>("TimeStepper")
      .def_readwrite("safety", &TimeStepper::safety)
      .def_readwrite("max_dt", &TimeStepper::maxDt)
      .def("stiffness_bound", &TimeStepper::stiffnessBound).staticmethod("stiffness_bound")
      .def("critical_pair_step", &TimeStepper::criticalPairStep).staticmethod("critical_pair_step");

  bp::class_<StressServo, bp::bases<Engine>, std::shared_ptr<StressServo>>("StressServo")
      .add_property("target", &getVec<StressServo, &StressServo::target>, &setVec<StressServo, &StressServo::target>)
      .def_readwrite("gain", &StressServo::gain)
      .def_readwrite("max_strain_rate", &StressServo::maxStrainRate)
      .def_readwrite("stress_tolerance", &StressServo::stressTolerance)
      .def_readwrite("unbalanced_tolerance", &StressServo::unbalancedTolerance)
      .def_readwrite("stop_when_reached", &StressServo::stopWhenReached)
      .add_property("stress", &getVec<StressServo, &StressServo::stress>)
      .def_readonly("unbalanced", &StressServo::unbalanced)
      .def_readonly("reached", &StressServo::reached);

  bp::class_<RadiusExpansion, bp::bases<Engine>, std::shared_ptr<RadiusExpansion>>("RadiusExpansion")
      .def_readwrite("target_pressure", &RadiusExpansion::targetPressure)
      .def_readwrite("gain", &RadiusExpansion::gain)
      .def_readwrite("max_growth_rate", &RadiusExpansion::maxGrowthRate)
      .def_readwrite("stress_tolerance", &RadiusExpansion::stressTolerance)
      .def_readwrite("unbalanced_tolerance", &RadiusExpansion::unbalancedTolerance)
      .def_readwrite("stop_when_reached", &RadiusExpansion::stopWhenReached)
      .def_readonly("scale", &RadiusExpansion::scale)
      .def_readonly("pressure", &RadiusExpansion::pressure)
      .def_readonly("unbalanced", &RadiusExpansion::unbalanced)
      .def_readonly("reached", &RadiusExpansion::reached);

  bp::class_<Simulation, std::shared_ptr<Simulation>>("Simulation", bp::init<std::shared_ptr<Scene>>())
      .def("add", &Simulation::add)
      .def("clear", &Simulation::clear)
      .def("run", &runSteps, "Run n steps; returns the steps done (fewer if an engine finished).")
      .add_property("engines", &engines)
      .add_property("scene", &Simulation::scenePtr);
}

}  // namespace trueaniso::py
