#pragma once
// StressProbe: control/StressProbe on O.cell.velGrad, with the snapshot and restore that our
// scene's probe does itself done here on YADE's scene. Included by TrueanisoYade.cpp.
#include <core/GlobalEngine.hpp>

#include <functional>
#include <memory>
#include <set>
#include <string>

#include "PythonAttributes.hpp"
#include "YadeRefusal.hpp"
#include "YadeScene.hpp"

namespace yade {

class StressProbe : public GlobalEngine {
  static constexpr const char* kName = "StressProbe";
  std::unique_ptr<trueaniso::StressProbe> k_;

 public:
  static const char* const* axisNames() {
    static const char* const names[6] = {"x", "y", "z", "yz", "xz", "xy"};
    return names;
  }
  static int axisIndex(const std::string& a) {
    for (int k = 0; k < 6; ++k)
      if (a == axisNames()[k]) return k;
    return -1;
  }
  // An axis as given from Python: one of the names, or its Voigt index 0-5.
  static std::string axisFrom(const boost::python::object& v) {
    boost::python::extract<std::string> s(v);
    if (s.check() && axisIndex(s()) >= 0) return s();
    boost::python::extract<long> i(v);
    if (!PyBool_Check(v.ptr()) && !s.check() && i.check() && i() >= 0 && i() < 6) return axisNames()[i()];
    const std::string shownValue = boost::python::extract<std::string>(boost::python::str(v))();
    trueanisoPlugin::refuse(kName, "axis", shownValue,
                            "must be one of x, y, z (Young's modulus and Poisson's ratios) or yz, xz, xy (shear "
                            "modulus), or their Voigt index 0-5");
  }
  std::string axisPy() const { return axis; }
  void setAxisPy(const boost::python::object& v) {
    axis = axisFrom(v);
    callPostLoad();
  }
  void pyHandleCustomCtorArgs(boost::python::tuple& /*t*/, boost::python::dict& d) override {
    if (d.has_key("axis")) d["axis"] = axisFrom(d["axis"]);
    trueanisoPlugin::PythonAttributes<StressProbe>::checkConstructorArguments(d, customAttributes());
  }

  // The kernel with this engine's parameters (not begun).
  trueaniso::StressProbe settings() const {
    trueaniso::StressProbe k;
    k.axis = axisIndex(axis);
    k.sign = sign;
    k.gammaTarget = gammaTarget;
    k.increment = increment;
    k.probeFriction = probeFriction;
    k.restrainRotations = restrainRotations;
    k.law.gain = gain;
    k.law.maxStrainRate = maxStrainRate;
    k.rampSteps = rampSteps;
    k.relativeTolerance = relativeTolerance;
    k.unbalancedTolerance = unbalancedTolerance;
    k.settleSteps = settleSteps;
    k.maxSteps = maxSteps;
    return k;
  }

  // Each attribute against the kernel's own range (a probe of defaults given that one value and a
  // valid hold, begun), holdStress alone (NaN entries: measured at the start; +-inf refused; a
  // normal entry given must be > 0). At construction, at each assignment and at O.load.
  void validate() const {
    namespace tp = trueanisoPlugin;
    using K = trueaniso::StressProbe;
    const trueaniso::Vec6 someHold = (trueaniso::Vec6() << 1e5, 1e5, 1e5, 0, 0, 0).finished();
    auto alone = [&](const char* name, auto value, const std::function<void(K&)>& set) {
      tp::checkAlone<K>(kName, name, tp::shown(value), set, [&](K& k) { k.begin(someHold); });
    };
    if (axisIndex(axis) < 0)
      tp::refuse(kName, "axis", "'" + axis + "'", "must be one of x, y, z, yz, xz, xy (or 0-5)");
    alone("sign", sign, [&](K& k) { k.sign = sign; });
    alone("gammaTarget", gammaTarget, [&](K& k) { k.gammaTarget = gammaTarget; });
    alone("increment", increment, [&](K& k) { k.increment = increment; });
    alone("probeFriction", probeFriction, [&](K& k) { k.probeFriction = probeFriction; });
    alone("gain", gain, [&](K& k) { k.law.gain = gain; });
    alone("maxStrainRate", maxStrainRate, [&](K& k) { k.law.maxStrainRate = maxStrainRate; });
    alone("rampSteps", rampSteps, [&](K& k) { k.rampSteps = rampSteps; });
    alone("relativeTolerance", relativeTolerance, [&](K& k) { k.relativeTolerance = relativeTolerance; });
    alone("unbalancedTolerance", unbalancedTolerance, [&](K& k) { k.unbalancedTolerance = unbalancedTolerance; });
    alone("settleSteps", settleSteps, [&](K& k) { k.settleSteps = settleSteps; });
    alone("maxSteps", maxSteps, [&](K& k) { k.maxSteps = maxSteps; });
    for (int i = 0; i < 6; ++i) {
      const Real h = holdStress[i];
      if (std::isnan(h)) continue;
      if (!std::isfinite(h) || (i < 3 && !(h > 0)))
        tp::refuse(kName, "holdStress", tp::shownVoigt(holdStress),
                   std::string("entry ") + axisNames()[i] + " is " + tp::shown(h) +
                       ": give finite stresses (Pa, compression positive; the normal ones > 0), or NaN for the "
                       "stress measured when the probe starts");
    }
  }
  void postLoad(StressProbe&) { validate(); }
  static std::set<std::string> customAttributes() { return {"axis"}; }  // axisFrom converts it

  void action() override;
  void resetPy();

 private:
  void snapshot();
  void clearHeld();
  // Puts back what the probe changed: friction and blocked DOFs and the cell's velocity gradient
  // always; with `whole`, the held state itself (positions, velocities, orientations, contact
  // forces, cell).
  void restore(bool whole);
  void finish(const trueaniso::StressProbe& k);

 public:
  // clang-format off
  YADE_CLASS_BASE_DOC_ATTRS_CTOR_PY(StressProbe, GlobalEngine,
    "The paper's directional stress probe (section 2.2, Eqs. 10-12), the code of the trueaniso engines "
    "(control/StressProbe.hpp). From the held state it suppresses sliding (friction probeFriction on every contact, "
    "every step), optionally restrains rotations, relaxes at the held stresses, raises the stress on ``axis`` while "
    "the five others are held until $\\gamma$ of Eq. (12) reaches gammaTarget (or the stress has risen by increment), "
    "holds to equilibrium, and gives E (Eq. 10) and nu (Eq. 11), or G for a shear axis. Then the scene is put back "
    "as it was (positions, velocities, orientations, cell and its velocity gradient, contact forces, friction, blocked "
    "DOFs). A scene saved mid-probe keeps the held state: loaded, the probe puts it back and probes again from it.\n\n"
    "Put it after InteractionLoop and before NewtonIntegrator, alone on the cell: a second active controller (an "
    "unfinished :yref:`TrueTriaxialServo`, another probe, PeriTriaxController, PeriIsoCompressor, Peri3dController) "
    "is refused at the first step. Particles: spheres and clumps of spheres; a clump is one particle, its contacts' "
    "branch vectors join clump centres.\n\n"
    "Conventions: stresses Voigt (xx, yy, zz, yz, xz, xy), compression positive, Pa (minus utils.getStress()); "
    "strains Voigt, engineering shears, compression positive, counted from the cell at the end of the relaxation; "
    "E and G in Pa, $\\nu_{ij} = -\\Delta\\varepsilon_j/\\Delta\\varepsilon_i$.\n\n"
    "Refusals: an attribute out of range raises ValueError at construction or assignment, naming it; a scene that "
    "is not periodic, a second controller, or held normal stresses that are not > 0 raise RuntimeError from O.run at "
    "the first step, before the probe changes anything. reset() mid-probe puts the held state back first.",
    ((string, axis, "z", Attr::triggerPostLoad, "x, y, z (E, nu) or yz, xz, xy (G); 0-5 are taken too"))
    ((int, sign, 1, Attr::triggerPostLoad, "+1 loads (compression or positive shear), -1 unloads"))
    ((Real, gammaTarget, 1e-6, Attr::triggerPostLoad, "strain at which the ramp stops: $\\gamma$ of Eq. (12), or the shear strain; finite, > 0"))
    ((Real, increment, 0, Attr::triggerPostLoad, "> 0: a fixed stress increment [Pa] instead of gammaTarget"))
    ((Real, probeFriction, 1e23, Attr::triggerPostLoad, "friction coefficient during the probe (the paper's sliding suppressed; the engines' kProbeFriction)"))
    ((bool, restrainRotations, false, , "block particle rotations during the probe"))
    ((Vector6r, holdStress, Vector6r::Constant(NAN), Attr::triggerPostLoad, "stresses held (Voigt, compression positive, Pa); a NaN entry holds the stress measured at the start"))
    ((Real, gain, 0.03, Attr::triggerPostLoad, "fraction of the stress error closed per step, in (0, 1]"))
    ((Real, maxStrainRate, 10.0, Attr::triggerPostLoad, "largest cell strain rate [1/s]; it only acts while relaxing, probes move strains of ~1e-6"))
    ((long, rampSteps, 300, Attr::triggerPostLoad, "expected length of the ramp (sets its rate)"))
    ((Real, relativeTolerance, 2e-3, Attr::triggerPostLoad, "stress error allowed, as a fraction of the increment, in (0, 1)"))
    ((Real, unbalancedTolerance, 1e-5, Attr::triggerPostLoad, "unbalanced force of the equilibrium (clumps as particles)"))
    ((long, settleSteps, 100, Attr::triggerPostLoad, "criteria met this many steps in a row"))
    ((long, maxSteps, 2000000, Attr::triggerPostLoad, "the probe fails after this many steps"))
    ((bool, restoreState, true, , "put the held state back when done (friction, blocked DOFs and the cell's velocity gradient are put back either way)"))
    ((bool, pauseWhenDone, true, , "stop O.run after the step where the probe ends"))
    ((bool, finished, false, Attr::readonly, "the probe has ended (see E, nu, G or message)"))
    ((Real, E, NAN, Attr::readonly, "Young's modulus of axis, Eq. (10) [Pa]"))
    ((Vector3r, nu, Vector3r::Constant(NAN), Attr::readonly, "Poisson's ratios $\\nu_{ij} = -\\Delta\\varepsilon_j/\\Delta\\varepsilon_i$, Eq. (11), for $j$ = x, y, z ($i$ = axis; NaN at $j = i$)"))
    ((Real, G, NAN, Attr::readonly, "shear modulus of a shear axis [Pa]"))
    ((Vector6r, dStress, Vector6r::Zero(), Attr::readonly, "stress increments (Voigt, compression positive) [Pa]"))
    ((Vector6r, dStrain, Vector6r::Zero(), Attr::readonly, "strain increments (Voigt, engineering shear, compression positive)"))
    ((Vector6r, heldStress, Vector6r::Constant(NAN), Attr::readonly, "the stresses held (holdStress, NaN entries measured at the start) [Pa]"))
    ((Vector6r, target, Vector6r::Zero(), Attr::readonly, "current goal [Pa]"))
    ((Real, stressError, 0, Attr::readonly, "largest distance of a held stress from its goal [Pa]"))
    ((Real, unbalanced, 0, Attr::readonly, "last unbalanced force"))
    ((Real, gamma, 0, Attr::readonly, "current $\\gamma$ of Eq. (12)"))
    ((int, stage, 0, Attr::readonly, "0 idle, 1 relax, 2 ramp, 3 hold, 4 done, 5 failed"))
    ((long, steps, 0, Attr::readonly, "steps of the probe"))
    ((long, lostContacts, 0, Attr::readonly, "contacts of the snapshot that no longer existed at the restore"))
    ((string, message, "", Attr::readonly, "why the probe failed"))
    ((Matrix3r, hSize0, Matrix3r::Identity(), Attr::readonly, "the cell when the probe started"))
    ((vector<Vector3r>, heldPos, , Attr::hidden, "held state: body positions"))
    ((vector<Vector3r>, heldVel, , Attr::hidden, "held state: body velocities"))
    ((vector<Vector3r>, heldAngVel, , Attr::hidden, "held state: body angular velocities"))
    ((vector<Quaternionr>, heldOri, , Attr::hidden, "held state: body orientations"))
    ((vector<int>, heldBlocked, , Attr::hidden, "held state: blockedDOFs"))
    ((vector<int>, heldId1, , Attr::hidden, "held state: first body of each contact"))
    ((vector<int>, heldId2, , Attr::hidden, "held state: second body of each contact"))
    ((vector<Vector3r>, heldNormalForce, , Attr::hidden, "held state: normal forces"))
    ((vector<Vector3r>, heldShearForce, , Attr::hidden, "held state: shear forces"))
    ((vector<Vector3r>, heldPrevNormal, , Attr::hidden, "held state: SimplifiedMindlinPhys.prevNormal"))
    ((vector<Vector3r>, heldRollingMoment, , Attr::hidden, "held state: SimplifiedMindlinPhys.rollingMoment"))
    ((vector<Vector3r>, heldGeomNormal, , Attr::hidden, "held state: ScGeom.normal"))
    ((vector<Real>, heldMu, , Attr::hidden, "held state: tan of the friction angle of each contact"))
    ((vector<Real>, heldDelta, , Attr::hidden, "held state: ScGeom.penetrationDepth"))
    ((vector<int>, heldLoaded, , Attr::hidden, "held state: SimplifiedMindlinPhys.loaded"))
    ((Matrix3r, heldHSize, Matrix3r::Identity(), Attr::hidden, "held state: cell hSize"))
    ((Matrix3r, heldTrsf, Matrix3r::Identity(), Attr::hidden, "held state: cell trsf"))
    ((Matrix3r, heldPrevHSize, Matrix3r::Identity(), Attr::hidden, "held state: cell prevHSize"))
    ((Matrix3r, heldVelGrad, Matrix3r::Zero(), Attr::hidden, "held state: cell velGrad")),
    /* ctor */,
    PYTHON_ATTRIBUTES_DEFS(StressProbe)
    .def("reset", &StressProbe::resetPy, "forget the results and probe again at the next step; mid-probe, the held state is put back first")
    .add_property("axis", &StressProbe::axisPy, &StressProbe::setAxisPy,
                  "x, y, z (E, nu) or yz, xz, xy (G); an index 0-5 is taken as its name :ydefault:`'z'` :yattrtype:`string`")
  );
  // clang-format on
};
REGISTER_SERIALIZABLE(StressProbe);

}  // namespace yade
