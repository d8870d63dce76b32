// Controllers (servos, radius expansion, stress probe) as seen from Python.
#include <memory>

#include "control/CellMeasurement.hpp"
#include "control/InertialNumber.hpp"
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
template <class E, Vec6 E::*F>
np::ndarray getVec6(const E& e) { return toNumpy(e.*F); }
template <class E>
np::ndarray principal(const E& e) { return toNumpy(e.gap.principal); }
template <class E>
Real maxShear(const E& e) { return e.gap.maxShear; }
template <class E>
Real stressError(const E& e) { return e.gap.error(); }

// StressServo: the three normal goals as `target`, all six as `goal`.
np::ndarray servoTarget(const StressServo& s) { return toNumpy(Vec3(s.goal.head<3>())); }
void setServoTarget(StressServo& s, const bp::object& o) { s.goal.head<3>() = toVec3(o, "servo target"); }
void setServoGoal(StressServo& s, const bp::object& o) { s.goal = toVec6(o, "servo goal"); }
bool servoControlsShear(const StressServo& s) { return (s.stressMask & kShearComponents) == kShearComponents; }
void setServoControlsShear(StressServo& s, bool on) {
  s.stressMask = on ? (s.stressMask | kShearComponents) : (s.stressMask & ~kShearComponents);
  if (!on) s.goal.tail<3>().setZero();  // held shear strains: rate 0
}

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
CellMeasurement measurement(const bp::object& stress, const bp::object& deformation, const bp::object& stiffness,
                            Real unbalanced) {
  CellMeasurement m;
  m.stress = toStressVoigt(stress, "stress");
  m.deformation = toMatrix3(deformation, "deformation gradient");
  m.stiffness = toVec6(stiffness, "stiffness");
  m.unbalanced = unbalanced;
  return m;
}
np::ndarray servoUpdate(TrueTriaxialServo& s, const bp::object& stress, const bp::object& deformation,
                        const bp::object& stiffness, Real unbalanced, Real dt) {
  return toNumpy(s.update(measurement(stress, deformation, stiffness, unbalanced), dt));
}
np::ndarray probeUpdate(StressProbe& p, const bp::object& stress, const bp::object& deformation,
                        const bp::object& stiffness, Real unbalanced, Real dt) {
  return toNumpy(p.update(measurement(stress, deformation, stiffness, unbalanced), dt));
}
np::ndarray cellStiffness(const Scene& s) { return toNumpy(CellMeasurement::of(s).stiffness); }
np::ndarray velocityGradientOf(const bp::object& rates) {
  return toNumpy(CellServoLaw::velocityGradient(toVec6(rates, "strain rates")));
}
np::ndarray strainBetweenPy(const bp::object& F0, const bp::object& F1) {
  return toNumpy(strainBetween(toMatrix3(F0, "F0"), toMatrix3(F1, "F1")));
}

}  // namespace

void exportControl() {
  bp::def("true_triaxial_stresses", &pathStresses, (bp::arg("b"), bp::arg("sigma_z"), bp::arg("p") = 100e3),
          "Eq. (9): (sigma_x, sigma_y, sigma_z) for b and p; raises ValueError for b outside [0, 1] or a "
          "principal stress <= 0.");
  bp::def("deviatoric_q", &pathQ, (bp::arg("b"), bp::arg("sigma_z"), bp::arg("p") = 100e3), "Eq. (13), signed.");
  bp::def("gamma", &gamma, "Eq. (12) from the three strain increments.");
  bp::def("strain_rate_for_inertial_number", &strainRateForInertialNumber,
          (bp::arg("inertial_number"), bp::arg("d50"), bp::arg("density"), bp::arg("pressure")),
          "Strain rate of inertial number I = rate d50 sqrt(rho/p) (1/s); ValueError unless every argument is finite "
          "and > 0.");

  bp::def("velocity_gradient", &velocityGradientOf, (bp::arg("rates")),
          "The cell's (symmetric) velocity gradient of six engineering strain rates (xx, yy, zz, yz, xz, xy).");
  bp::def("strain_between", &strainBetweenPy, (bp::arg("F0"), bp::arg("F1")),
          "Log strain from deformation gradient F0 to F1, Voigt, engineering shears, compression positive.");
  bp::scope().attr("NORMAL_COMPONENTS") = kNormalComponents;
  bp::scope().attr("SHEAR_COMPONENTS") = kShearComponents;
  bp::scope().attr("ALL_COMPONENTS") = kAllComponents;

  bp::class_<StressServo, bp::bases<Engine>, std::shared_ptr<StressServo>>("StressServo")
      .add_property("target", &servoTarget, &setServoTarget, "Goals of the three normal stresses (Pa).")
      .add_property("goal", &getVec6<StressServo, &StressServo::goal>, &setServoGoal,
                    "Six goals (xx, yy, zz, yz, xz, xy): stresses for components under stress control, engineering "
                    "strain rates for the others.")
      .def_readwrite("stress_mask", &StressServo::stressMask, "Bit I set: Voigt component I under stress control.")
      .add_property("control_shear", &servoControlsShear, &setServoControlsShear,
                    "Servo the three shear stresses (default) or hold the shear strains.")
      .add_property("gain", &getGain<StressServo>, &setGain<StressServo>)
      .add_property("max_strain_rate", &getRate<StressServo>, &setRate<StressServo>)
      .def_readwrite("stress_tolerance", &StressServo::stressTolerance)
      .def_readwrite("unbalanced_tolerance", &StressServo::unbalancedTolerance)
      .def_readwrite("stop_when_reached", &StressServo::stopWhenReached)
      .add_property("stress", &getVec6<StressServo, &StressServo::stress>)
      .add_property("principal", &principal<StressServo>, "Principal stresses, largest first (Pa).")
      .add_property("max_shear", &maxShear<StressServo>, "Largest |off-diagonal stress| (Pa).")
      .add_property("stress_error", &stressError<StressServo>,
                    "Largest principal or component error against the goals (Pa).")
      .def_readonly("unbalanced", &StressServo::unbalanced)
      .def_readonly("reached", &StressServo::reached);

  bp::class_<RadiusExpansion, bp::bases<Engine>, std::shared_ptr<RadiusExpansion>>("RadiusExpansion")
      .def_readwrite("target_pressure", &RadiusExpansion::targetPressure)
      .def_readwrite("gain", &RadiusExpansion::gain)
      .def_readwrite("max_growth_rate", &RadiusExpansion::maxGrowthRate)
      .def_readwrite("stress_tolerance", &RadiusExpansion::stressTolerance)
      .def_readwrite("unbalanced_tolerance", &RadiusExpansion::unbalancedTolerance)
      .def_readwrite("stop_when_reached", &RadiusExpansion::stopWhenReached)
      .def_readwrite("hold_deviator", &RadiusExpansion::holdDeviator,
                     "Strain the cell at constant volume so that the normal stresses stay at their mean while the radii grow.")
      .def_readwrite("deviator_gain", &RadiusExpansion::deviatorGain,
                     "Gain of the deviator hold: the fraction of sigma_k - p closed per step through the affine stiffness.")
      .def_readonly("deviator", &RadiusExpansion::deviator, "Largest |sigma_k - p| over the normal stresses (Pa).")
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
      .add_property("goal_stresses", &goalStresses, "Eq. (9): sigma_x, sigma_y, sigma_z of the state.")
      .add_property("final_stress", +[](const TrueTriaxialServo& s) { return toNumpy(s.finalStress()); },
                    "The state's six stresses (Voigt): Eq. (9) and the shear goals.")
      .add_property("shear_goal", &getVec<TrueTriaxialServo, &TrueTriaxialServo::shearGoal>,
                    &setVec<TrueTriaxialServo, &TrueTriaxialServo::shearGoal>, "sigma_yz, sigma_xz, sigma_xy at the state.")
      .def_readwrite("control_shear", &TrueTriaxialServo::controlShear,
                     "Servo the shear stresses (default) or hold the cell's shear strains.")
      .def("validate", &TrueTriaxialServo::validate)
      .add_property("gain", &getGain<TrueTriaxialServo>, &setGain<TrueTriaxialServo>)
      .add_property("max_strain_rate", &getRate<TrueTriaxialServo>, &setRate<TrueTriaxialServo>)
      .def_readwrite("path_rate", &TrueTriaxialServo::pathRate, "Pa per reference step along the path")
      .def_readwrite("step_scale", &TrueTriaxialServo::stepScale,
                     "The step in reference steps, taken from the scene at every step (path rate, gain and step counts are per reference step).")
      .def_readwrite("feed_forward", &TrueTriaxialServo::feedForward,
                     "Feed the goal's motion forward through the cell's measured tangent stiffness (default off).")
      .add_property("tangent_ratio", +[](const TrueTriaxialServo& s) { return toNumpy(s.tangent.ratio()); },
                    "The cell's tangent stiffness over its affine estimate, per Voigt component, as measured.")
      .add_property("tangent_memory", +[](const TrueTriaxialServo& s) { return s.tangent.memory; },
                    +[](TrueTriaxialServo& s, Real v) { s.tangent.memory = v; s.tangent.validate(); },
                    "Steps over which the tangent ratio is measured (fading weights).")
      .def_readonly("lag", &TrueTriaxialServo::lag, "Largest |stress - goal| now (Pa).")
      .def_readonly("waited", &TrueTriaxialServo::waited,
                    "Steps the goal waited for a stress more than follow_tolerance behind it.")
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
      .add_property("stress", &getVec6<TrueTriaxialServo, &TrueTriaxialServo::stress>, "Voigt, compression positive.")
      .add_property("target", &getVec6<TrueTriaxialServo, &TrueTriaxialServo::target>)
      .add_property("overshoot", &getVec6<TrueTriaxialServo, &TrueTriaxialServo::overshoot>,
                    "Largest excursion of each stress past its goal in the loading direction (Pa).")
      .add_property("principal", &principal<TrueTriaxialServo>, "Principal stresses, largest first (Pa).")
      .add_property("max_shear", &maxShear<TrueTriaxialServo>, "Largest |off-diagonal stress| (Pa).")
      .add_property("stress_error", &stressError<TrueTriaxialServo>,
                    "Largest principal or shear-stress error against the state (Pa).")
      .def_readonly("unbalanced", &TrueTriaxialServo::unbalanced)
      .def_readonly("steps", &TrueTriaxialServo::steps)
      .def("update", &servoUpdate,
           (bp::arg("stress"), bp::arg("deformation"), bp::arg("stiffness"), bp::arg("unbalanced"), bp::arg("dt")),
           "Control logic without a scene (YADE adapter): six engineering strain rates from a measurement.");

  bp::class_<StressProbe, bp::bases<Engine>, std::shared_ptr<StressProbe>>("StressProbe")
      .def("start", +[](StressProbe& p, Scene& s, const bp::object& hold) { p.start(s, toStressVoigt(hold, "held stresses")); },
           (bp::arg("scene"), bp::arg("hold")),
           "Snapshot the scene, suppress sliding, begin relaxing at the held stresses.")
      .def("restore", &StressProbe::restore, "Put the snapshot back into the scene.")
      .def_readwrite("axis", &StressProbe::axis, "0, 1, 2 = x, y, z; 3, 4, 5 = yz, xz, xy (checked by start/begin)")
      .def_readwrite("control_shear", &StressProbe::controlShear,
                     "Hold the shear stresses (default) or the cell's shear strains (x, y, z probes only).")
      .def_readwrite("hold_other_strains", &StressProbe::holdOtherStrains,
                     "Hold the five other strains instead of their stresses: the probe measures C_kk, not 1/S_kk.")
      .def_readwrite("sign", &StressProbe::sign,
                     "+1 loads, -1 unloads (checked by start/begin); two-sided: the first side's")
      .def_readwrite("two_sided", &StressProbe::twoSided,
                     "Run a second side with -sign from the relaxed state; the increments are the half differences.")
      .def_readwrite("gamma_target", &StressProbe::gammaTarget, "Eq. (12) at which the ramp stops")
      .def_readwrite("increment", &StressProbe::increment)
      .def_readwrite("probe_friction", &StressProbe::probeFriction)
      .def_readwrite("restrain_rotations", &StressProbe::restrainRotations)
      .add_property("gain", &getGain<StressProbe>, &setGain<StressProbe>)
      .add_property("max_strain_rate", &getRate<StressProbe>, &setRate<StressProbe>)
      .def_readwrite("ramp_steps", &StressProbe::rampSteps, "The ramp's length in reference steps (sets its rate).")
      .def_readwrite("step_scale", &StressProbe::stepScale,
                     "The step in reference steps, taken from the scene at every step (gain and step counts are per reference step).")
      .def_readwrite("relative_tolerance", &StressProbe::relativeTolerance)
      .def_readwrite("unbalanced_tolerance", &StressProbe::unbalancedTolerance)
      .def_readwrite("settle_steps", &StressProbe::settleSteps)
      .def_readwrite("max_steps", &StressProbe::maxSteps)
      .add_property("stage", &probeStage)
      .def_readonly("message", &StressProbe::message)
      .add_property("ref_stress", &getVec6<StressProbe, &StressProbe::refStress>)
      .add_property("stress", &getVec6<StressProbe, &StressProbe::stress>)
      .add_property("target", &getVec6<StressProbe, &StressProbe::target>)
      .add_property("d_stress", &getVec6<StressProbe, &StressProbe::dStress>, "Voigt stress increment (Pa).")
      .add_property("d_strain", &getVec6<StressProbe, &StressProbe::dStrain>,
                    "Voigt strain increment (engineering shears), compression positive.")
      .add_property("d_stress_first", &getVec6<StressProbe, &StressProbe::dStressFirst>,
                    "The first side's stress increment.")
      .add_property("d_strain_first", &getVec6<StressProbe, &StressProbe::dStrainFirst>,
                    "The first side's strain increment.")
      .add_property("d_stress_second", &getVec6<StressProbe, &StressProbe::dStressSecond>,
                    "A two-sided probe's second side (with -sign): its stress increment.")
      .add_property("d_strain_second", &getVec6<StressProbe, &StressProbe::dStrainSecond>,
                    "A two-sided probe's second side: its strain increment.")
      .def_readonly("side", &StressProbe::side, "0: the first side (or Relax), 1: the second")
      .def_readonly("gamma", &StressProbe::gamma)
      .def_readonly("unbalanced", &StressProbe::unbalanced)
      .def_readonly("steps", &StressProbe::steps)
      .def_readonly("relax_steps", &StressProbe::relaxSteps)
      .def_readonly("ramp_steps_done", &StressProbe::rampStepsDone)
      .def_readonly("hold_steps", &StressProbe::holdSteps)
      .add_property("young_modulus", &StressProbe::youngModulus)
      .add_property("modulus", &StressProbe::modulus, "E_i (x, y, z probes) or G_ij (yz, xz, xy): d stress / d strain.")
      .def("poisson_ratio", &poisson)
      .def("begin", +[](StressProbe& p, const bp::object& hold) { p.begin(toStressVoigt(hold, "held stresses")); },
           "Reset the stages without a scene (YADE adapter).")
      .def("update", &probeUpdate,
           (bp::arg("stress"), bp::arg("strain"), bp::arg("stiffness"), bp::arg("unbalanced"), bp::arg("dt")),
           "Control logic without a scene (YADE adapter): strain rates from a measurement.");
  bp::def("cell_stiffness", &cellStiffness,
          "Affine stiffness estimate per Voigt component (xx, yy, zz, yz, xz, xy) the controllers use (Pa).");
}

}  // namespace trueaniso::py
