// The YADE plugin: our contact law, true-triaxial servo, stress probe and fabric recorder as YADE
// classes (docs/yade-peer.md). One translation unit, because every file that includes YADE's
// headers costs about a minute and 4 GB to compile (engines/yade/CMakeLists.txt); the classes live
// in the headers beside it, one concern each.
//
// Every class here is an adapter: it reads YADE's scene (interactions, bodies, cell), hands the
// numbers to the code of engines/ that our own stepper runs, and writes the answer back into
// YADE (forces, O.cell.velGrad, attributes). The physics is written once, in engines/.
#include <core/Clump.hpp>
#include <core/Dispatching.hpp>
#include <core/GlobalEngine.hpp>
#include <core/Omega.hpp>
#include <core/Scene.hpp>
#include <core/State.hpp>
#include <core/ThreadRunner.hpp>
#include <pkg/common/Box.hpp>
#include <pkg/common/ElastMat.hpp>
#include <pkg/common/Facet.hpp>
#include <pkg/common/PeriodicEngines.hpp>
#include <pkg/common/Sphere.hpp>
#include <pkg/common/Wall.hpp>
#include <pkg/dem/FrictPhys.hpp>
#include <pkg/dem/ScGeom.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <vector>

// Our engines, hidden: their inline functions, vtables and type information must bind to this
// library's copies, compiled with YADE's Eigen definitions, never to those of our Python module
// (the same names, compiled with Eigen's default alignment) when both are loaded in one session.
// YADE's headers and Eigen come first, so that only our own declarations fall under the pragma.
#pragma GCC visibility push(hidden)
#include "clump/UnionOfBalls.hpp"
#include "contact/HertzMindlin.hpp"
#include "contact/MaterialPair.hpp"
#include "control/CellMeasurement.hpp"
#include "control/CellServoLaw.hpp"
#include "control/InertialNumber.hpp"
#include "control/StressProbe.hpp"
#include "control/TrueTriaxialServo.hpp"
#include "measure/ContactTerms.hpp"
#include "measure/Fabric.hpp"
#include "measure/FabricTerms.hpp"
#pragma GCC visibility pop

namespace yade {
// Our engines use Eigen doubles; YADE's Real is double in yade-double (YADE_REAL_BIT=64), so its
// vectors and matrices are the same types and pass through unchanged.
static_assert(std::is_same<Real, double>::value, "the trueaniso plugin is for yade-double");
}  // namespace yade

#include "AbiCheck.hpp"
#include "ContactLaw.hpp"
#include "FabricRecorderEngine.hpp"
#include "ProbeEngine.hpp"
#include "ServoEngine.hpp"

namespace yade {

// YADE's docs show a default as written: the probe's friction is written as its value there, and
// must stay the engines' one home of it.
static_assert(trueaniso::kProbeFriction == 1e23, "StressProbe.probeFriction's default is kProbeFriction");
static_assert(trueaniso::kLoadingFriction == 0.5, "TrueTriaxialServo.loadingFriction's default is kLoadingFriction");

namespace {
std::string labelled(const Engine& e) { return e.label.empty() ? std::string() : " '" + e.label + "'"; }

// Refusals that need the scene, before an engine changes it: a periodic cell, one controller.
void checkCellFor(const Engine& e, Scene* scene) {
  const std::string who = e.getClassName() + labelled(e);
  if (!scene->isPeriodic)
    throw std::runtime_error(who + " needs a periodic cell (O.periodic=True): it controls O.cell");
  const std::string other = trueanisoPlugin::otherCellController<TrueTriaxialServo, StressProbe>(scene, &e);
  if (!other.empty())
    throw std::runtime_error(who + ": O.engines also holds " + other +
                             ", an active controller of the cell; two controllers of one cell work against each other: "
                             "remove one from O.engines (or set its dead=True) before O.run");
}
}  // namespace

// ---------------------------------------------------------------------------------------------
// TrueTriaxialServo

Real TrueTriaxialServo::computeRateCap() const {
  if (maxStrainRate > 0) return maxStrainRate;
  std::vector<Real> radii;
  Real density = 0;
  for (const auto& b : *scene->bodies)
    if (b)
      if (const auto* s = dynamic_cast<const Sphere*>(b->shape.get())) {
        radii.push_back(s->radius);
        if (density == 0 && b->material) density = b->material->density;
      }
  if (radii.empty()) throw std::runtime_error("TrueTriaxialServo: the scene has no spheres (its strain-rate cap is "
                                              "that of inertialNumber for their median diameter: set maxStrainRate)");
  std::sort(radii.begin(), radii.end());
  const std::size_t n = radii.size();
  const Real median = n % 2 ? radii[n / 2] : 0.5 * (radii[n / 2 - 1] + radii[n / 2]);
  return trueaniso::strainRateForInertialNumber(inertialNumber, 2.0 * median, density, meanStress);
}

void TrueTriaxialServo::action() {
  if (reached || failed) return;
  trueanisoPlugin::refusingInLoop([&] {
    checkCellFor(*this, scene);
    if (status == 0) {  // first step: every check first, then the cell's reference
      validate();
      rateCap = computeRateCap();
    }
  });
  if (status == 0) hSize0 = scene->cell->hSize;
  trueaniso::TrueTriaxialServo k = kernel();
  k.law.maxStrainRate = rateCap;
  trueanisoPlugin::setFriction(scene, loadingFriction);
  const trueaniso::Vec6 rates = k.update(trueanisoPlugin::measureCell<SimplifiedMindlinPhys>(scene, hSize0), scene->dt);
  store(k);
  scene->cell->setVelGrad(trueaniso::CellServoLaw::velocityGradient(rates));
  if ((reached || failed) && pauseWhenDone) trueanisoPlugin::stopNextStep(scene);
}

// ---------------------------------------------------------------------------------------------
// StressProbe

void StressProbe::snapshot() {
  const std::size_t nb = scene->bodies->size();
  heldPos.assign(nb, Vector3r::Zero());
  heldVel.assign(nb, Vector3r::Zero());
  heldAngVel.assign(nb, Vector3r::Zero());
  heldOri.assign(nb, Quaternionr::Identity());
  heldBlocked.assign(nb, 0);
  for (std::size_t i = 0; i < nb; ++i) {
    const auto& b = (*scene->bodies)[i];
    if (!b) continue;
    const State& st = *b->state;
    heldPos[i] = st.pos;
    heldVel[i] = st.vel;
    heldAngVel[i] = st.angVel;
    heldOri[i] = st.ori;
    heldBlocked[i] = static_cast<int>(st.blockedDOFs);
  }
  heldId1.clear(); heldId2.clear(); heldNormalForce.clear(); heldShearForce.clear(); heldPrevNormal.clear();
  heldRollingMoment.clear(); heldGeomNormal.clear(); heldMu.clear(); heldDelta.clear(); heldLoaded.clear();
  for (const auto& I : *scene->interactions) {
    if (!I->isReal()) continue;
    auto* g = dynamic_cast<ScGeom*>(I->geom.get());
    auto* p = dynamic_cast<FrictPhys*>(I->phys.get());
    if (!g || !p) continue;
    auto* sp = dynamic_cast<SimplifiedMindlinPhys*>(p);
    heldId1.push_back(I->getId1());
    heldId2.push_back(I->getId2());
    heldNormalForce.push_back(p->normalForce);
    heldShearForce.push_back(p->shearForce);
    heldPrevNormal.push_back(sp ? sp->prevNormal : Vector3r::Zero());
    heldRollingMoment.push_back(sp ? sp->rollingMoment : Vector3r::Zero());
    heldGeomNormal.push_back(g->normal);
    heldMu.push_back(p->tangensOfFrictionAngle);
    heldDelta.push_back(g->penetrationDepth);
    heldLoaded.push_back(sp && sp->loaded ? 1 : 0);
  }
  heldHSize = scene->cell->hSize;
  heldTrsf = scene->cell->trsf;
  heldPrevHSize = scene->cell->prevHSize;
  heldVelGrad = scene->cell->velGradChanged ? scene->cell->nextVelGrad : scene->cell->velGrad;
}

void StressProbe::clearHeld() {
  for (auto* v : {&heldPos, &heldVel, &heldAngVel, &heldNormalForce, &heldShearForce, &heldPrevNormal,
                  &heldRollingMoment, &heldGeomNormal})
    v->clear();
  for (auto* v : {&heldBlocked, &heldId1, &heldId2, &heldLoaded}) v->clear();
  heldOri.clear();
  heldMu.clear();
  heldDelta.clear();
}

void StressProbe::restore(bool whole) {
  for (std::size_t i = 0; i < heldPos.size() && i < scene->bodies->size(); ++i) {
    const auto& b = (*scene->bodies)[i];
    if (!b) continue;
    State& st = *b->state;
    st.blockedDOFs = static_cast<unsigned>(heldBlocked[i]);
    if (!whole) continue;
    st.pos = heldPos[i];
    st.vel = heldVel[i];
    st.angVel = heldAngVel[i];
    st.ori = heldOri[i];
  }
  // Contacts made during the probe get their materials' friction (what the Ip2 gives them), those
  // of the snapshot their own.
  for (const auto& I : *scene->interactions) {
    auto* p = dynamic_cast<FrictPhys*>(I->phys.get());
    if (!p) continue;
    const auto* m1 = dynamic_cast<const FrictMat*>(Body::byId(I->getId1(), scene)->material.get());
    const auto* m2 = dynamic_cast<const FrictMat*>(Body::byId(I->getId2(), scene)->material.get());
    if (m1 && m2) p->tangensOfFrictionAngle = std::tan(std::min(m1->frictionAngle, m2->frictionAngle));
  }
  lostContacts = 0;
  for (std::size_t c = 0; c < heldId1.size(); ++c) {
    const shared_ptr<Interaction> I = scene->interactions->find(heldId1[c], heldId2[c]);
    if (!I || !I->isReal()) {
      ++lostContacts;
      continue;
    }
    auto* g = dynamic_cast<ScGeom*>(I->geom.get());
    auto* p = dynamic_cast<FrictPhys*>(I->phys.get());
    if (!g || !p) {
      ++lostContacts;
      continue;
    }
    p->tangensOfFrictionAngle = heldMu[c];
    if (!whole) continue;
    p->normalForce = heldNormalForce[c];
    p->shearForce = heldShearForce[c];
    g->normal = heldGeomNormal[c];
    g->penetrationDepth = heldDelta[c];
    if (auto* sp = dynamic_cast<SimplifiedMindlinPhys*>(p)) {
      sp->prevNormal = heldPrevNormal[c];
      sp->rollingMoment = heldRollingMoment[c];
      sp->loaded = heldLoaded[c] != 0;
    }
  }
  Cell& cell = *scene->cell;
  if (whole) {
    cell.hSize = heldHSize;
    cell.trsf = heldTrsf;
    cell.prevHSize = heldPrevHSize;
  }
  cell.setVelGrad(heldVelGrad);
  cell.velGrad = cell.prevVelGrad = heldVelGrad;
  if (whole) cell.integrateAndUpdate(0);
}

void StressProbe::finish(const trueaniso::StressProbe& k) {
  dStress = TrueTriaxialServo::fromVec6(k.dStress);
  dStrain = TrueTriaxialServo::fromVec6(k.dStrain);
  message = k.message;
  if (k.stage == trueaniso::StressProbe::Stage::Done) {
    if (k.shearProbe()) {
      G = k.modulus();
    } else {
      E = k.youngModulus();
      for (int j = 0; j < 3; ++j) nu[j] = j == k.axis ? NAN : k.poissonRatio(j);
    }
  }
  restore(restoreState);
  clearHeld();  // a scene saved after the probe need not carry it
  finished = true;
  k_.reset();
  if (pauseWhenDone) trueanisoPlugin::stopNextStep(scene);
}

void StressProbe::action() {
  if (finished) return;
  trueanisoPlugin::refusingInLoop([&] { checkCellFor(*this, scene); });
  const bool loadedMidProbe = !k_ && stage >= 1 && stage <= 3 && !heldPos.empty();
  if (!k_) {
    // Every check before the scene changes: the attributes, then the kernel begun on a copy with
    // the stresses it would hold (it refuses held normal stresses that are not > 0).
    trueanisoPlugin::refusingInLoop([&] { validate(); });
    if (loadedMidProbe) restore(true);  // loaded mid-probe: from the held state, as if never interrupted
    trueaniso::StressProbe k = settings();
    const Matrix3r h = scene->cell->hSize;
    const trueaniso::CellMeasurement m0 = trueanisoPlugin::measureCell<SimplifiedMindlinPhys>(scene, h);
    trueaniso::Vec6 hold = TrueTriaxialServo::toVec6(loadedMidProbe ? heldStress : holdStress);
    for (int i = 0; i < 6; ++i)
      if (std::isnan(hold[i])) hold[i] = m0.stress[i];
    try {
      k.begin(hold);
    } catch (const std::exception& e) {
      trueanisoPlugin::letPythonWait();
      throw std::runtime_error("StressProbe" + labelled(*this) + ": " + e.what() +
                               " (holdStress NaN entries take the stress measured now: is the packing loaded?)");
    }
    // From here on the scene changes.
    hSize0 = h;
    heldStress = TrueTriaxialServo::fromVec6(hold);
    if (!loadedMidProbe) snapshot();
    if (restrainRotations)
      for (const auto& b : *scene->bodies)
        if (b) {
          b->state->blockedDOFs |= State::DOF_RXRYRZ;
          b->state->angVel = Vector3r::Zero();
        }
    k_.reset(new trueaniso::StressProbe(k));
    finished = false;
    E = G = NAN;
    nu = Vector3r::Constant(NAN);
  }
  trueanisoPlugin::setFriction(scene, probeFriction);  // every step: contacts made during the probe too
  trueaniso::StressProbe& k = *k_;
  const trueaniso::Vec6 rates = k.update(trueanisoPlugin::measureCell<SimplifiedMindlinPhys>(scene, hSize0), scene->dt);
  steps = k.steps;
  stage = static_cast<int>(k.stage);
  gamma = k.gamma;
  target = TrueTriaxialServo::fromVec6(k.target);
  unbalanced = k.unbalanced;
  Real err = 0;
  for (int i = 0; i < 6; ++i)
    if (k.stressMask() >> i & 1u) err = std::max(err, std::abs(k.stress[i] - k.target[i]));
  stressError = err;
  if (k.stage == trueaniso::StressProbe::Stage::Done || k.stage == trueaniso::StressProbe::Stage::Failed) {
    finish(k);
    return;
  }
  scene->cell->setVelGrad(trueaniso::CellServoLaw::velocityGradient(rates));
}

void StressProbe::resetPy() {
  if (!scene) scene = Omega::instance().getScene().get();
  const bool midProbe = !finished && stage >= 1 && stage <= 3 && !heldPos.empty();
  if (midProbe) restore(true);  // friction, DOFs, the cell and its rate, positions: as the probe found them
  clearHeld();
  finished = false;
  k_.reset();
  E = G = NAN;
  nu = Vector3r::Constant(NAN);
  dStress = dStrain = Vector6r::Zero();
  stage = 0;
  steps = 0;
  gamma = 0;
  message.clear();
}

YADE_PLUGIN((SimplifiedMindlinPhys)(Ip2_FrictMat_FrictMat_SimplifiedMindlinPhys)(Law2_ScGeom_SimplifiedMindlinPhys_Mindlin)
            (TrueanisoAbiCheck)(TrueTriaxialServo)(StressProbe)(FabricRecorder));

}  // namespace yade
