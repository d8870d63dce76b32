// Engines and the simulation loop as seen from Python. Parameters are validated by the engines
// themselves when they run and by the Python layer before a run starts.
#include <memory>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "core/Parallel.hpp"
#include "dynamics/ContactDetection.hpp"
#include "dynamics/ContactForces.hpp"
#include "dynamics/ContactRefresh.hpp"
#include "dynamics/NewtonIntegrator.hpp"
#include "dynamics/Simulation.hpp"
#include "dynamics/TimeStepper.hpp"
#include "python/Numpy.hpp"
#include "EngineSourceHash.hpp"  // generated at build time (cmake/EngineSourceHash.cmake)

namespace trueaniso::py {

namespace {

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

int maxThreads() {
#ifdef _OPENMP
  return omp_get_max_threads();
#else
  return 1;
#endif
}
void setThreads(int n) {
  require(n >= 1, "number of threads must be >= 1");
#ifdef _OPENMP
  omp_set_num_threads(n);
#endif
}

void exportEngines() {
  bp::def("threads", &maxThreads, "OpenMP threads the engines use.");
  bp::def("source_hash", +[]() { return std::string(kEngineSourceHash); },
          "SHA-256 of the engine sources this module was compiled from (cmake/EngineSourceHash.cmake).");
  bp::def("build_arch", +[]() { return std::string(TRUEANISO_ARCH_NAME); },
          "The x86-64 level the module was compiled for: x86-64 (the portable baseline) or TRUEANISO_ARCH "
          "(x86-64-v2, -v3, -v4), whose results differ in the last bits (CMakeLists.txt).");
  bp::def("set_threads", &setThreads, "Set the OpenMP threads of the engines (OMP_NUM_THREADS is read only at start).");
  bp::def("parallel_minimum", &parallelMinimum,
          "Loops shorter than this many items (contacts, bodies) run on one thread (core/Parallel.hpp).");
  bp::def("set_parallel_minimum", +[](int items) {
    require(items >= 0, "the parallel minimum is a number of items >= 0");
    setParallelMinimum(items);
  }, "Set parallel_minimum (0: every loop in a team). Like the thread count, it changes the last bits of results.");
  bp::class_<Engine, std::shared_ptr<Engine>, boost::noncopyable>("Engine", bp::no_init)
      .def("apply", &Engine::apply)
      .add_property("name", &Engine::name)
      .def_readwrite("every", &Engine::every)
      .def_readwrite("dead", &Engine::dead)
      .def_readonly("applied", &Engine::applied)
      .def_readwrite("done", &Engine::done);

  bp::class_<ContactDetection, bp::bases<Engine>, std::shared_ptr<ContactDetection>>("ContactDetection")
      .def_readwrite("skin_factor", &ContactDetection::skinFactor)
      .def_readonly("rebuilds", &ContactDetection::rebuilds)
      .def_readonly("lost_contacts", &ContactDetection::lostContacts)
      .def("rebuild", &ContactDetection::rebuild)
      .def("needs_rebuild", &ContactDetection::needsRebuild);

  bp::def("refresh_contacts", &refreshContacts, (bp::arg("scene")),
          "Contact list, normals, branches and forces for the current positions, no tangential increment "
          "(tangential forces carried bit for bit where the contact frame is unchanged).");
  bp::scope().attr("PROBE_FRICTION") = kProbeFriction;
  bp::scope().attr("LOADING_FRICTION") = kLoadingFriction;

  bp::class_<ContactForces, bp::bases<Engine>, std::shared_ptr<ContactForces>>("ContactForces")
      .def_readonly("sliding_contacts", &ContactForces::slidingContacts)
      .def_readonly("rolling_capped", &ContactForces::rollingCapped);

  bp::class_<NewtonIntegrator, bp::bases<Engine>, std::shared_ptr<NewtonIntegrator>>("NewtonIntegrator")
      .def_readwrite("damping", &NewtonIntegrator::damping)
      .def_readwrite("check_every", &NewtonIntegrator::checkEvery);

  bp::class_<TimeStepper, bp::bases<Engine>, std::shared_ptr<TimeStepper>>("TimeStepper")
      .def_readwrite("safety", &TimeStepper::safety)
      .def_readwrite("max_dt", &TimeStepper::maxDt)
      .def("stiffness_bound", &TimeStepper::stiffnessBound).staticmethod("stiffness_bound")
      .def("critical_pair_step", &TimeStepper::criticalPairStep).staticmethod("critical_pair_step");

  bp::class_<Simulation, std::shared_ptr<Simulation>>("Simulation", bp::init<std::shared_ptr<Scene>>())
      .def("add", &Simulation::add)
      .def("clear", &Simulation::clear)
      .def("run", &runSteps, "Run n steps; returns the steps done (fewer if an engine finished).")
      .add_property("engines", &engines)
      .add_property("scene", &Simulation::scenePtr);
}

}  // namespace trueaniso::py
