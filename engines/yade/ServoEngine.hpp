#pragma once
// TrueTriaxialServo: control/TrueTriaxialServo on O.cell.velGrad. Included by TrueanisoYade.cpp.
#include <core/GlobalEngine.hpp>

#include <functional>
#include <set>
#include <string>

#include "PythonAttributes.hpp"
#include "YadeRefusal.hpp"
#include "YadeScene.hpp"

namespace yade {

class StressProbe;

class TrueTriaxialServo : public GlobalEngine {
  static constexpr const char* kName = "TrueTriaxialServo";

 public:
  void action() override;

  // Our servo with this engine's parameters and state.
  trueaniso::TrueTriaxialServo kernel() const {
    trueaniso::TrueTriaxialServo k = settings();
    k.status = static_cast<trueaniso::TrueTriaxialServo::Status>(status);
    k.progress = progress;
    k.startStress = toVec6(startStress);
    k.target = toVec6(target);
    k.startDeformation = startDeformation;
    k.overshoot = toVec6(overshoot);
    k.steps = steps;
    k.settled = settled;
    k.stalled = stalled;
    k.holding = holding;
    k.waited = waited;
    return k;
  }
  // The parameters alone (a servo that has not started).
  trueaniso::TrueTriaxialServo settings() const {
    trueaniso::TrueTriaxialServo k;
    k.goal.b = b;
    k.goal.sigmaZ = sigmaZ;
    k.goal.p = meanStress;
    k.law.gain = gain;
    k.law.maxStrainRate = maxStrainRate > 0 ? maxStrainRate : 1.0;  // 0: from inertialNumber at the first step
    k.loadingFriction = loadingFriction;
    k.pathRate = pathRate;
    k.followTolerance = followTolerance;
    k.stressTolerance = stressTolerance;
    k.unbalancedTolerance = unbalancedTolerance;
    k.settleSteps = settleSteps;
    k.maxStrain = maxStrain;
    k.maxSteps = maxSteps;
    k.stallSteps = stallSteps;
    k.holdSteps = holdSteps;
    k.stepScale = stepScale;
    k.lostStressFraction = lostStressFraction;
    return k;
  }
  void store(const trueaniso::TrueTriaxialServo& k) {
    status = static_cast<int>(k.status);
    progress = k.progress;
    startStress = fromVec6(k.startStress);
    target = fromVec6(k.target);
    stress = fromVec6(k.stress);
    startDeformation = k.startDeformation;
    overshoot = fromVec6(k.overshoot);
    steps = k.steps;
    settled = k.settled;
    stalled = k.stalled;
    holding = k.holding;
    waited = k.waited;
    unbalanced = k.unbalanced;
    stressError = k.gap.error();
    message = k.message;
    reached = k.status == trueaniso::TrueTriaxialServo::Status::Reached;
    failed = k.status == trueaniso::TrueTriaxialServo::Status::Failed;
  }

  // Each attribute against the kernel's own range (a servo of defaults given that one value, so a
  // message names the attribute), then b, sigmaZ and meanStress together (Eq. 9: every principal
  // stress > 0). At construction, at each assignment (PythonAttributes) and at O.load.
  void validate() const {
    namespace tp = trueanisoPlugin;
    using K = trueaniso::TrueTriaxialServo;
    auto alone = [](const char* name, auto value, const std::function<void(K&)>& set) {
      tp::checkAlone<K>(kName, name, tp::shown(value), set, [](K& k) { k.validate(); });
    };
    // the goal's three numbers alone: at an isotropic state, which any b in [0, 1] keeps valid
    alone("b", b, [&](K& k) { k.goal.b = b; });
    if (!(std::isfinite(sigmaZ) && sigmaZ > 0)) tp::refuse(kName, "sigmaZ", tp::shown(sigmaZ), "sigma_z must be a finite stress > 0 (Pa, compression positive)");
    if (!(std::isfinite(meanStress) && meanStress > 0)) tp::refuse(kName, "meanStress", tp::shown(meanStress), "the mean stress p must be a finite stress > 0 (Pa, compression positive)");
    alone("pathRate", pathRate, [&](K& k) { k.pathRate = pathRate; });
    alone("followTolerance", followTolerance, [&](K& k) { k.followTolerance = followTolerance; });
    alone("stressTolerance", stressTolerance, [&](K& k) { k.stressTolerance = stressTolerance; });
    alone("unbalancedTolerance", unbalancedTolerance, [&](K& k) { k.unbalancedTolerance = unbalancedTolerance; });
    alone("settleSteps", settleSteps, [&](K& k) { k.settleSteps = settleSteps; });
    alone("maxStrain", maxStrain, [&](K& k) { k.maxStrain = maxStrain; });
    alone("maxSteps", maxSteps, [&](K& k) { k.maxSteps = maxSteps; });
    alone("stallSteps", stallSteps, [&](K& k) { k.stallSteps = stallSteps; });
    alone("holdSteps", holdSteps, [&](K& k) { k.holdSteps = holdSteps; });
    alone("gain", gain, [&](K& k) { k.law.gain = gain; });
    if (maxStrainRate != 0) alone("maxStrainRate", maxStrainRate, [&](K& k) { k.law.maxStrainRate = maxStrainRate; });
    alone("loadingFriction", loadingFriction, [&](K& k) { k.loadingFriction = loadingFriction; });
    alone("stepScale", stepScale, [&](K& k) { k.stepScale = stepScale; });
    alone("lostStressFraction", lostStressFraction, [&](K& k) { k.lostStressFraction = lostStressFraction; });
    try {
      trueaniso::strainRateForInertialNumber(inertialNumber, 1.0, 1.0, 1.0);
    } catch (const std::exception& e) {
      tp::refuse(kName, "inertialNumber", tp::shown(inertialNumber), e.what());
    }
    try {
      settings().goal.validate();
    } catch (const std::exception& e) {
      throw std::invalid_argument(std::string(kName) + " (b = " + tp::shown(b) + ", sigmaZ = " + tp::shown(sigmaZ) +
                                  ", meanStress = " + tp::shown(meanStress) + "): " + e.what() +
                                  " (to change them together: servo.updateAttrs(dict(b=..., sigmaZ=..., meanStress=...)))");
    }
  }
  void postLoad(TrueTriaxialServo&) { validate(); }
  static std::set<std::string> customAttributes() { return {}; }
  void pyHandleCustomCtorArgs(boost::python::tuple& /*t*/, boost::python::dict& d) override {
    trueanisoPlugin::PythonAttributes<TrueTriaxialServo>::checkConstructorArguments(d);
  }

  // The cell's strain-rate cap: maxStrainRate, or (0) that of inertialNumber for the median sphere
  // diameter, the first sphere's density and meanStress, as our stepper's reach_state takes it.
  Real computeRateCap() const;

  // clang-format off
  YADE_CLASS_BASE_DOC_ATTRS_CTOR_PY(TrueTriaxialServo, GlobalEngine,
    "The paper's b-controlled true-triaxial servo at constant mean stress (section 2.2, Eqs. 8-9), the code of the "
    "trueaniso engines (control/TrueTriaxialServo.hpp). From the stresses it finds at its first step it moves its "
    "goal along the straight path to the state (b, sigmaZ, meanStress) as fast as the specimen follows, holds the "
    "three shear stresses at zero on the full 3x3 cell, and sets :yref:`Cell.velGrad` every step; ``reached`` turns "
    "true when every stress is within stressTolerance and the unbalanced force below unbalancedTolerance for "
    "settleSteps steps in a row, ``failed`` (with ``message``) when the specimen cannot carry the state.\n\n"
    "Put it after InteractionLoop and before NewtonIntegrator, alone on the cell: a second active controller "
    "(another servo, an unfinished :yref:`StressProbe`, PeriTriaxController, PeriIsoCompressor, Peri3dController) is "
    "refused at the first step. Particles: spheres and clumps of spheres; a clump is one particle, its contacts' "
    "branch vectors join clump centres (YADE's getStress takes the same).\n\n"
    "Conventions: stresses are Voigt (xx, yy, zz, yz, xz, xy), compression positive, in Pa: ``stress`` is minus the "
    "symmetric part of utils.getStress(). Strain rates are engineering, extension positive. The per-step settings "
    "(pathRate, gain, the step counts) are per step of stepScale (1: YADE's own step).\n\n"
    "Refusals: an attribute out of range raises ValueError at construction or assignment, naming it; a scene that "
    "is not periodic, or a second controller of the cell, raises RuntimeError from O.run at the first step, before "
    "the servo changes anything. Friction: from its first step the servo sets loadingFriction on every contact, "
    "every step (contacts made later too, from the step after they appear).",
    ((Real, b, 0, Attr::triggerPostLoad, "intermediate principal stress coefficient of Eq. (8), in [0, 1]"))
    ((Real, sigmaZ, 100e3, Attr::triggerPostLoad, "$\\sigma_z$ of the state [Pa], > 0"))
    ((Real, meanStress, 100e3, Attr::triggerPostLoad, "mean stress $p$, constant along the path [Pa], > 0"))
    ((Real, pathRate, 2.0, Attr::triggerPostLoad, "fastest motion of the goal along the path [Pa per step], > 0"))
    ((Real, followTolerance, 1000.0, Attr::triggerPostLoad, "the goal advances while every stress is within this of it [Pa]"))
    ((Real, stressTolerance, 500.0, Attr::triggerPostLoad, "a state is held when every stress (shear too) is within this [Pa]"))
    ((Real, unbalancedTolerance, 1e-4, Attr::triggerPostLoad, "and YADE's unbalanced force (clumps as particles) below this"))
    ((long, settleSteps, 200, Attr::triggerPostLoad, "for this many steps in a row"))
    ((Real, maxStrain, 0.05, Attr::triggerPostLoad, "the specimen fails when a cell strain since the start exceeds this"))
    ((long, maxSteps, 3000000, Attr::triggerPostLoad, "the servo fails after this many steps"))
    ((long, stallSteps, 100000, Attr::triggerPostLoad, "it fails when the specimen has not followed the goal for this many steps in a row"))
    ((long, holdSteps, 200000, Attr::triggerPostLoad, "it fails when held at the state this many steps without settling"))
    ((Real, gain, 0.01, Attr::triggerPostLoad, "fraction of the stress error closed per step, in (0, 1]"))
    ((Real, maxStrainRate, 0, Attr::triggerPostLoad, "largest cell strain rate [1/s]; 0: that of inertialNumber"))
    ((Real, inertialNumber, 1e-3, Attr::triggerPostLoad, "with maxStrainRate 0, the cap is the strain rate $\\dot\\varepsilon$ of this inertial number $I = \\dot\\varepsilon\\, d_{50} \\sqrt{\\rho/p}$: $d_{50}$ the median sphere diameter, $\\rho$ the first sphere's density, $p$ = meanStress (quasi-static below 1e-3)"))
    ((Real, loadingFriction, 0.5, Attr::triggerPostLoad, "friction coefficient set on every contact while the servo runs (the paper's 0.5)"))
    ((Real, lostStressFraction, 0.5, Attr::triggerPostLoad, "a normal stress below this fraction of its goal (a packing that lost its stress when its friction dropped, a cloud) is loaded at the strain-rate cap, not by the stiffness of the few contacts left; 0: never"))
    ((Real, stepScale, 1.0, Attr::triggerPostLoad, "length of a step in the unit of the per-step settings (1: YADE's step; run_states.py --host yade passes O.dt over the reference rule's step)"))
    ((bool, pauseWhenDone, true, , "stop O.run after the step where the state is reached or fails"))
    ((bool, reached, false, Attr::readonly, "the state is held within tolerance"))
    ((bool, failed, false, Attr::readonly, "the specimen could not carry the state (see message)"))
    ((string, message, "", Attr::readonly, "why it failed"))
    ((Real, progress, 0, Attr::readonly, "0 at the start stresses, 1 at the state"))
    ((Vector6r, stress, Vector6r::Zero(), Attr::readonly, "last measured stress (Voigt xx yy zz yz xz xy, compression positive) [Pa]"))
    ((Real, stressError, 0, Attr::readonly, "largest stress error against the state, shear included [Pa]"))
    ((Real, unbalanced, 0, Attr::readonly, "last unbalanced force"))
    ((Real, rateCap, 0, Attr::readonly, "the cap the servo runs with [1/s] (maxStrainRate, or that of inertialNumber)"))
    ((int, status, 0, Attr::readonly, "0 idle, 1 loading, 2 holding, 3 reached, 4 failed"))
    ((Vector6r, startStress, Vector6r::Zero(), Attr::readonly, "stresses when the servo started [Pa]"))
    ((Vector6r, target, Vector6r::Zero(), Attr::readonly, "current goal on the path [Pa]"))
    ((Matrix3r, startDeformation, Matrix3r::Identity(), Attr::readonly, "cell deformation when the servo started"))
    ((Matrix3r, hSize0, Matrix3r::Identity(), Attr::readonly, "the cell when the servo started"))
    ((Vector6r, overshoot, Vector6r::Constant(-1e300), Attr::readonly, "largest excursion of each stress beyond its goal [Pa]"))
    ((long, steps, 0, Attr::readonly, "steps run"))
    ((long, settled, 0, Attr::readonly, "steps in a row within tolerance"))
    ((long, stalled, 0, Attr::readonly, "steps in a row without following the goal"))
    ((long, holding, 0, Attr::readonly, "steps held at the state"))
    ((long, waited, 0, Attr::readonly, "steps the goal waited for the specimen, in all")),
    /* ctor */,
    PYTHON_ATTRIBUTES_DEFS(TrueTriaxialServo)
    .def("finalStress", &TrueTriaxialServo::finalStressPy, "the six stresses of the state (Eq. 9), Voigt, compression positive, Pa")
  );
  // clang-format on
  Vector6r finalStressPy() const { return fromVec6(settings().finalStress()); }

  static trueaniso::Vec6 toVec6(const Vector6r& v) { return trueaniso::Vec6(v[0], v[1], v[2], v[3], v[4], v[5]); }
  static Vector6r fromVec6(const trueaniso::Vec6& v) {
    Vector6r r;
    for (int k = 0; k < 6; ++k) r[k] = v[k];
    return r;
  }
};
REGISTER_SERIALIZABLE(TrueTriaxialServo);

}  // namespace yade
