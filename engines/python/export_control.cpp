// Controllers (servos, radius expansion, stress probe) as seen from Python.
#include <memory>

#include "control/CellMeasurement.hpp"
#include "control/RadiusExpansion.hpp"
#include "control/StressProbe.hpp"
#include "control/StressServo.hpp"
#include "control/TrueTriaxialPath.hpp"
#include "control/TrueTriaxialServo.hpp"
#include "python/Numpy.hpp"

namespace trueaniso::py {

namespace {

template <class E, Vec3 E::*F>
np::ndarray getVec(const E& e) { return toNumpy(e.*F); }
template <class E, Vec3 E::*F>
void setVec(E& e, const bp::object& o) { e.*F = toVec3(o, "vector parameter"); }

// The servo law's parameters appear as attributes of the engine that owns it.
template <class E> Real getGain(const E& e) { return e.law.gain; }
template <class E> void setGain(E& e, Real v) { e.law.gain = v; e.law.validate(); }
template <class E> Real getRate(const E& e) { return e.law.maxStrainRate; }
template <class E> void setRate(E& e, Real v) { e.law.maxStrainRate = v; e.law.validate(); }

np::ndarray pathStresses(Real b, Real sigmaZ, Real p) {
  TrueTriaxialState st{b, sigmaZ, p};
  st.validate();
  return toNumpy(st.stresses());
}
Real pathQ(Real b, Real sigmaZ, Real p) {
  TrueTriaxialState st{b, sigmaZ, p};
  st.validate();
  return st.q();
}
Real gamma(const bp::object& de) { return shearStrainGamma(toVec3(de, "strain increments")); }

const char* servoStatus(const TrueTriaxialServo& s) {
  switch (s.status) {
    case TrueTriaxialServo::Status::Idle: return "idle";
    case TrueTriaxialServo::Status::Loading: return "loading";
    case TrueTriaxialServo::Status::Holding: return "holding";
    case TrueTriaxialServo::Status::Reached: return "reached";
    case TrueTriaxialServo::Status::Failed: return "failed";
  }
  return "?";
}
void setGoal(TrueTriaxialServo& s, Real b, Real sigmaZ, Real p) {
  TrueTriaxialState st{b, sigmaZ, p};
  st.validate();
  s.goal = st;
  s.reset();
}
Real goalB(const TrueTriaxialServo& s) { return s.goal.b; }
Real goalSz(const TrueTriaxialServo& s) { return s.goal.sigmaZ; }
Real goalP(const TrueTriaxialServo& s) { return s.goal.p; }
np::ndarray goalStresses(const TrueTriaxialServo& s) { return toNumpy(s.goal.stresses()); }

const char* probeStage(const StressProbe& p) {
  switch (p.stage) {
    case StressProbe::Stage::Idle: return "idle";
    case StressProbe::Stage::Relax: return "relax";
    case StressProbe::Stage::Ramp: return "ramp";
    case StressProbe::Stage::Hold: return "hold";
    case StressProbe::Stage::Done: return "done";
    case StressProbe::Stage::Failed: return "failed";
  }
  return "?";
}
Real poisson(const StressProbe& p, int j) { return p.poissonRatio(j); }

// The control logic of an engine without a scene, for the YADE adapter: measurement in, strain
// rates out (numpy arrays).
CellMeasurement measurement(const bp::object& stress, const bp::object& strain, const bp::object& stiffness,
                            Real unbalanced) {
  CellMeasurement m;
  m.stress = toVec3(stress, "stress");
  m.strain = toVec3(strain, "strain");
  m.stiffness = toVec3(stiffness, "stiffness");
  m.unbalanced = unbalanced;
  return m;
}
np::ndarray servoUpdate(TrueTriaxialServo& s, const bp::object& stress, const bp::object& strain,
                        const bp::object& stiffness, Real unbalanced, Real dt) {
  return toNumpy(s.update(measurement(stress, strain, stiffness, unbalanced), dt));
}
np::ndarray probeUpdate(StressProbe& p, const bp::object& stress, const bp::object& strain,
                        const bp::object& stiffness, Real unbalanced, Real dt) {
  return toNumpy(p.update(measurement(stress, strain, stiffness, unbalanced), dt));
}
np::ndarray cellStiffness(const Scene& s) { return toNumpy(CellMeasurement::of(s).stiffness); }

}  // namespace

void exportControl() {
  bp::def("true_triaxial_stresses", &pathStresses, (bp::arg("b"), bp::arg("sigma_z"), bp::arg("p") = 100e3),
          "Eq. (9): (sigma_x, sigma_y, sigma_z) for b and p; raises ValueError for b outside [0, 1] or a "
          "principal stress <= 0.");
  bp::def("deviatoric_q", &pathQ, (bp::arg("b"), bp::arg("sigma_z"), bp::arg("p") = 100e3), "Eq. (13), signed.");
  bp::def("gamma", &gamma, "Eq. (12) from the three strain increments.");

  bp::class_<StressServo, bp::bases<Engine>, std::shared_ptr<StressServo>>("StressServo")
      .add_property("target", &getVec<StressServo, &StressServo::target>, &setVec<StressServo, &StressServo::target>)
      .add_property("gain", &getGain<StressServo>, &setGain<StressServo>)
      .add_property("max_strain_rate", &getRate<StressServo>, &setRate<StressServo>)
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

  bp::class_<TrueTriaxialServo, bp::bases<Engine>, std::shared_ptr<TrueTriaxialServo>>("TrueTriaxialServo")
      .def("set_goal", &setGoal, (bp::arg("b"), bp::arg("sigma_z"), bp::arg("p") = 100e3),
           "Validate and set the state to reach; resets the servo.")
      .def("reset", &TrueTriaxialServo::reset)
      .def("start", &TrueTriaxialServo::start, (bp::arg("scene")),
           "Validate the parameters and set the loading friction on the scene; required before running.")
      .def_readwrite("loading_friction", &TrueTriaxialServo::loadingFriction,
                     "Friction of every contact while loading (the paper's 0.5), set by start().")
      .add_property("b", &goalB)
      .add_property("sigma_z", &goalSz)
      .add_property("p", &goalP)
      .add_property("goal_stresses", &goalStresses)
      .add_property("gain", &getGain<TrueTriaxialServo>, &setGain<TrueTriaxialServo>)
      .add_property("max_strain_rate", &getRate<TrueTriaxialServo>, &setRate<TrueTriaxialServo>)
      .def_readwrite("path_rate", &TrueTriaxialServo::pathRate, "Pa per step along the path")
      .def_readwrite("follow_tolerance", &TrueTriaxialServo::followTolerance)
      .def_readwrite("stress_tolerance", &TrueTriaxialServo::stressTolerance)
      .def_readwrite("unbalanced_tolerance", &TrueTriaxialServo::unbalancedTolerance)
      .def_readwrite("settle_steps", &TrueTriaxialServo::settleSteps)
      .def_readwrite("max_strain", &TrueTriaxialServo::maxStrain)
      .def_readwrite("max_steps", &TrueTriaxialServo::maxSteps)
      .def_readwrite("stall_steps", &TrueTriaxialServo::stallSteps)
      .def_readwrite("hold_steps", &TrueTriaxialServo::holdSteps)
      .def_readonly("holding", &TrueTriaxialServo::holding)
      .add_property("status", &servoStatus)
      .def_readonly("message", &TrueTriaxialServo::message)
      .def_readonly("progress", &TrueTriaxialServo::progress)
      .add_property("stress", &getVec<TrueTriaxialServo, &TrueTriaxialServo::stress>)
      .add_property("target", &getVec<TrueTriaxialServo, &TrueTriaxialServo::target>)
      .add_property("overshoot", &getVec<TrueTriaxialServo, &TrueTriaxialServo::overshoot>,
                    "Largest excursion of each stress past its goal in the loading direction (Pa).")
      .def_readonly("unbalanced", &TrueTriaxialServo::unbalanced)
      .def_readonly("steps", &TrueTriaxialServo::steps)
      .def("update", &servoUpdate,
           (bp::arg("stress"), bp::arg("strain"), bp::arg("stiffness"), bp::arg("unbalanced"), bp::arg("dt")),
           "Control logic without a scene (YADE adapter): strain rates from a measurement.");

  bp::class_<StressProbe, bp::bases<Engine>, std::shared_ptr<StressProbe>>("StressProbe")
      .def("start", +[](StressProbe& p, Scene& s, const bp::object& hold) { p.start(s, toVec3(hold, "held stresses")); },
           (bp::arg("scene"), bp::arg("hold")),
           "Snapshot the scene, suppress sliding, begin relaxing at the held stresses.")
      .def("restore", &StressProbe::restore, "Put the snapshot back into the scene.")
      .def_readwrite("axis", &StressProbe::axis, "0, 1, 2 = x, y, z (checked by start/begin)")
      .def_readwrite("sign", &StressProbe::sign, "+1 loads, -1 unloads (checked by start/begin)")
      .def_readwrite("gamma_target", &StressProbe::gammaTarget, "Eq. (12) at which the ramp stops")
      .def_readwrite("increment", &StressProbe::increment)
      .def_readwrite("probe_friction", &StressProbe::probeFriction)
      .def_readwrite("restrain_rotations", &StressProbe::restrainRotations)
      .add_property("gain", &getGain<StressProbe>, &setGain<StressProbe>)
      .add_property("max_strain_rate", &getRate<StressProbe>, &setRate<StressProbe>)
      .def_readwrite("ramp_steps", &StressProbe::rampSteps)
      .def_readwrite("relative_tolerance", &StressProbe::relativeTolerance)
      .def_readwrite("unbalanced_tolerance", &StressProbe::unbalancedTolerance)
      .def_readwrite("settle_steps", &StressProbe::settleSteps)
      .def_readwrite("max_steps", &StressProbe::maxSteps)
      .add_property("stage", &probeStage)
      .def_readonly("message", &StressProbe::message)
      .add_property("ref_stress", &getVec<StressProbe, &StressProbe::refStress>)
      .add_property("stress", &getVec<StressProbe, &StressProbe::stress>)
      .add_property("target", &getVec<StressProbe, &StressProbe::target>)
      .add_property("d_stress", &getVec<StressProbe, &StressProbe::dStress>)
      .add_property("d_strain", &getVec<StressProbe, &StressProbe::dStrain>)
      .def_readonly("gamma", &StressProbe::gamma)
      .def_readonly("unbalanced", &StressProbe::unbalanced)
      .def_readonly("steps", &StressProbe::steps)
      .def_readonly("relax_steps", &StressProbe::relaxSteps)
      .def_readonly("ramp_steps_done", &StressProbe::rampStepsDone)
      .def_readonly("hold_steps", &StressProbe::holdSteps)
      .add_property("young_modulus", &StressProbe::youngModulus)
      .def("poisson_ratio", &poisson)
      .def("begin", +[](StressProbe& p, const bp::object& hold) { p.begin(toVec3(hold, "held stresses")); },
           "Reset the stages without a scene (YADE adapter).")
      .def("update", &probeUpdate,
           (bp::arg("stress"), bp::arg("strain"), bp::arg("stiffness"), bp::arg("unbalanced"), bp::arg("dt")),
           "Control logic without a scene (YADE adapter): strain rates from a measurement.");
  bp::def("cell_stiffness", &cellStiffness, "Affine axial stiffness estimate the controllers use (Pa).");
}

}  // namespace trueaniso::py
