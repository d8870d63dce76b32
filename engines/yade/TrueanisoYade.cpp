// The YADE plugin: our contact law, true-triaxial servo, stress probe and fabric recorder as YADE
// classes (docs/yade-peer.md). One translation unit, because every file that includes YADE's
// headers costs about a minute and 4 GB to compile (engines/yade/CMakeLists.txt).
//
// Every class here is an adapter: it reads YADE's scene (interactions, bodies, cell), hands the
// numbers to the code of engines/ that our own stepper runs, and writes the answer back into
// YADE (forces, O.cell.velGrad, attributes). The physics is written once, in engines/.
#include <core/Omega.hpp>
#include <core/Scene.hpp>
#include <core/State.hpp>
#include <core/Dispatching.hpp>
#include <pkg/common/ElastMat.hpp>
#include <pkg/common/PeriodicEngines.hpp>
#include <pkg/common/Sphere.hpp>
#include <pkg/dem/FrictPhys.hpp>
#include <pkg/dem/ScGeom.hpp>

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
#include "contact/HertzMindlin.hpp"
#include "control/CellMeasurement.hpp"
#include "control/CellServoLaw.hpp"
#include "control/StressProbe.hpp"
#include "control/TrueTriaxialServo.hpp"
#include "measure/ContactTerms.hpp"
#include "measure/Fabric.hpp"
#include "measure/FabricTerms.hpp"
#pragma GCC visibility pop

namespace yade {

namespace ta = trueaniso;

// Our engines use Eigen doubles; YADE's Real is double in yade-double (YADE_REAL_BIT=64), so its
// vectors and matrices are the same types and pass through unchanged.
static_assert(std::is_same<Real, double>::value, "the trueaniso plugin is for yade-double");

namespace {
ta::Vec6 toVec6(const Vector6r& v) { return ta::Vec6(v[0], v[1], v[2], v[3], v[4], v[5]); }
Vector6r fromVec6(const ta::Vec6& v) {
  Vector6r r;
  for (int k = 0; k < 6; ++k) r[k] = v[k];
  return r;
}
const Real kNaN = std::numeric_limits<Real>::quiet_NaN();
}  // namespace

// ---------------------------------------------------------------------------------------------
// The contact law of the paper (Eqs. 5-7), contact/HertzMindlin.hpp.

class SimplifiedMindlinPhys : public FrictPhys {
 public:
  ta::HertzMindlin law() const {
    return ta::HertzMindlin(ta::HertzMindlin::Constants{stiffnessRatio, tangensOfFrictionAngle, Cn, Cs, hertzUnit,
                                                        rollingStiffness, rollingFriction});
  }
  virtual ~SimplifiedMindlinPhys() = default;
  // clang-format off
  YADE_CLASS_BASE_DOC_ATTRS_CTOR(SimplifiedMindlinPhys, FrictPhys,
    "The paper's simplified Hertz-Mindlin contact (Eqs. 5-7) of the trueaniso engines: Hertz's normal force, "
    "the tangential stiffness k_s = (C_s/C_n) k_n of Eq. (6) carried with the contact frame by an exact rotation, "
    "Coulomb's cap at tangensOfFrictionAngle times N (set it to 1e23 to suppress sliding, as the probe does), "
    "an optional rolling spring. Made by :yref:`Ip2_FrictMat_FrictMat_SimplifiedMindlinPhys`.",
    ((Real, rbar, 0, , "r-bar of Eq. (7), 2 r1 r2/(r1 + r2) [m]"))
    ((Real, hertzUnit, 0, , "(4/3) E* sqrt(1/2): N = hertzUnit sqrt(rbar) delta^(3/2) [Pa]"))
    ((Real, stiffnessRatio, 0, , "k_s/k_n = C_s/C_n = 2(1-nu)/(2-nu)"))
    ((Real, Cn, 0, , "C_n of Eq. (5)"))
    ((Real, Cs, 0, , "C_s of Eq. (6)"))
    ((Real, rollingStiffness, 0, , "beta of the rolling spring k_r = beta k_s rbar^2 (0: no rolling resistance)"))
    ((Real, rollingFriction, 0, , "eta_r: the rolling moment is capped at eta_r rbar N"))
    ((Vector3r, rollingMoment, Vector3r::Zero(), , "rolling moment on body 2 [N m]"))
    ((Vector3r, prevNormal, Vector3r::Zero(), , "the contact normal at the last evaluation"))
    ((bool, loaded, false, , "the contact carried a force at the last evaluation"))
    ((bool, isSliding, false, , "at the Coulomb cap after the last evaluation")),
    createIndex());
  // clang-format on
  REGISTER_CLASS_INDEX(SimplifiedMindlinPhys, FrictPhys);
};
REGISTER_SERIALIZABLE(SimplifiedMindlinPhys);

class Ip2_FrictMat_FrictMat_SimplifiedMindlinPhys : public IPhysFunctor {
 public:
  void go(const shared_ptr<Material>& m1, const shared_ptr<Material>& m2, const shared_ptr<Interaction>& I) override {
    if (I->phys) return;
    const auto* a = YADE_CAST<FrictMat*>(m1.get());
    const auto* b = YADE_CAST<FrictMat*>(m2.get());
    // The paper's law is for identical spheres' material (Eqs. 5-7 are written with one G and nu).
    if (a->young != b->young || a->poisson != b->poisson)
      throw std::invalid_argument("Ip2_FrictMat_FrictMat_SimplifiedMindlinPhys: both materials must have the same "
                                  "young and poisson (the paper's law is for one material)");
    ta::Material m;
    m.poisson = a->poisson;
    m.shearModulus = a->young / (2.0 * (1.0 + a->poisson));
    m.friction = std::tan(std::min(a->frictionAngle, b->frictionAngle));
    m.rollingStiffness = rollingStiffness;
    m.rollingFriction = rollingFriction;
    const ta::HertzMindlin::Constants c = ta::HertzMindlin::constants(m);
    auto p = shared_ptr<SimplifiedMindlinPhys>(new SimplifiedMindlinPhys());
    p->hertzUnit = c.hertzUnit;
    p->stiffnessRatio = c.ratio;
    p->Cn = c.Cn;
    p->Cs = c.Cs;
    p->rollingStiffness = c.beta;
    p->rollingFriction = c.etaR;
    p->tangensOfFrictionAngle = c.mu;
    const auto* g = YADE_CAST<GenericSpheresContact*>(I->geom.get());
    const Real r1 = g->refR1 > 0 ? g->refR1 : g->refR2, r2 = g->refR2 > 0 ? g->refR2 : g->refR1;
    p->rbar = 2.0 * r1 * r2 / (r1 + r2);
    I->phys = p;
  }
  FUNCTOR2D(FrictMat, FrictMat);
  // clang-format off
  YADE_CLASS_BASE_DOC_ATTRS(Ip2_FrictMat_FrictMat_SimplifiedMindlinPhys, IPhysFunctor,
    "Makes :yref:`SimplifiedMindlinPhys` from two FrictMat of one material: G = young/(2(1+poisson)), nu = poisson "
    "(the particle's Poisson ratio, as in :yref:`Ip2_FrictMat_FrictMat_MindlinPhys`), friction tan(min(frictionAngle)).",
    ((Real, rollingStiffness, 0, , "beta of the rolling spring (0: none)"))
    ((Real, rollingFriction, 0, , "eta_r of the rolling cap")));
  // clang-format on
};
REGISTER_SERIALIZABLE(Ip2_FrictMat_FrictMat_SimplifiedMindlinPhys);

class Law2_ScGeom_SimplifiedMindlinPhys_Mindlin : public LawFunctor {
 public:
  bool go(shared_ptr<IGeom>& ig, shared_ptr<IPhys>& ip, Interaction* I) override {
    auto* g = static_cast<ScGeom*>(ig.get());
    auto* p = static_cast<SimplifiedMindlinPhys*>(ip.get());
    const Real delta = g->penetrationDepth;
    if (delta < 0) {
      if (!neverErase) return false;
      p->normalForce = p->shearForce = p->rollingMoment = Vector3r::Zero();
      p->kn = p->ks = 0;
      p->loaded = false;
      return true;
    }
    const Body::id_t id1 = I->getId1(), id2 = I->getId2();
    const State* s1 = Body::byId(id1, scene)->state.get();
    const State* s2 = Body::byId(id2, scene)->state.get();
    const Real dt = scene->dt;
    const Vector3r& n = g->normal;
    // The pair's spin about the current normal, and the tangential relative displacement of the
    // step (YADE's kinematics, computed by Ig2 as for its own laws).
    const Real twist = 0.5 * dt * n.dot(s1->angVel + s2->angVel);
    const ta::HertzMindlin law = p->law();
    const ta::HertzMindlin::Response r =
        law.evaluate(delta, p->rbar, n, p->loaded, p->prevNormal, p->shearForce, g->shearIncrement(), twist);
    p->normalForce = r.N * n;
    p->shearForce = r.Fs;
    p->isSliding = r.sliding;
    p->kn = ta::HertzMindlin::normalStiffness(r.N, delta);
    p->ks = law.shearStiffness(p->kn);
    const Vector3r prev = p->prevNormal;
    const bool wasLoaded = p->loaded;
    p->prevNormal = n;
    p->loaded = r.N > 0;
    const Vector3r force = -p->normalForce - p->shearForce;  // on body 1
    scene->forces.addForce(id1, force);
    scene->forces.addForce(id2, -force);
    scene->forces.addTorque(id1, (g->radius1 - 0.5 * delta) * n.cross(force));
    scene->forces.addTorque(id2, (g->radius2 - 0.5 * delta) * n.cross(force));
    if (p->rollingStiffness > 0) {
      const Vector3r dw = (s2->angVel - s1->angVel) * dt;
      bool capped = false;
      p->rollingMoment = law.rollingMoment(p->rbar, r.N, p->ks, n, wasLoaded, prev, p->rollingMoment,
                                           dw - n.dot(dw) * n, twist, capped);
      scene->forces.addTorque(id1, -p->rollingMoment);
      scene->forces.addTorque(id2, p->rollingMoment);
    }
    return true;
  }
  FUNCTOR2D(ScGeom, SimplifiedMindlinPhys);
  // clang-format off
  YADE_CLASS_BASE_DOC_ATTRS(Law2_ScGeom_SimplifiedMindlinPhys_Mindlin, LawFunctor,
    "The paper's simplified Hertz-Mindlin law (Eqs. 5-7), the code of the trueaniso engines "
    "(contact/HertzMindlin.hpp): N = (4/3) E* sqrt(rbar/2) delta^(3/2), the shear force carried with the contact "
    "frame by an exact rotation and incremented by -k_s times the step's tangential displacement, capped at "
    "tangensOfFrictionAngle N; the rolling spring when the phys has rollingStiffness > 0.",
    ((bool, neverErase, false, , "keep interactions whose spheres separated (forces zero)")));
  // clang-format on
};
REGISTER_SERIALIZABLE(Law2_ScGeom_SimplifiedMindlinPhys_Mindlin);

// ---------------------------------------------------------------------------------------------
// The ABI self-test's engine: what it reads of the scene must be what Python reads.

class TrueanisoAbiCheck : public GlobalEngine {
 public:
  void action() override {
    iters.push_back(static_cast<Real>(scene->iter));
    times.push_back(scene->time);
    dts.push_back(scene->dt);
    cellVolumes.push_back(scene->isPeriodic ? scene->cell->hSize.determinant() : 0.0);
    bodyCount = static_cast<int>(scene->bodies->size());
  }
  // clang-format off
  YADE_CLASS_BASE_DOC_ATTRS(TrueanisoAbiCheck, GlobalEngine,
    "Records scene->iter, time, dt and the cell volume every step: the build's self-test compares them with "
    "O.iter, O.time, O.dt and O.cell.volume read from Python.",
    ((vector<Real>, iters, , Attr::readonly, "scene->iter at each call"))
    ((vector<Real>, times, , Attr::readonly, "scene->time at each call"))
    ((vector<Real>, dts, , Attr::readonly, "scene->dt at each call"))
    ((vector<Real>, cellVolumes, , Attr::readonly, "det(hSize) at each call"))
    ((int, bodyCount, 0, Attr::readonly, "scene->bodies->size()")));
  // clang-format on
};
REGISTER_SERIALIZABLE(TrueanisoAbiCheck);

// ---------------------------------------------------------------------------------------------
// The cell measurement our controllers read (control/CellMeasurement.hpp), on YADE's scene: the
// Love-Weber stress and the affine stiffness from the same per-contact terms as our stepper
// (measure/ContactTerms.hpp), YADE's unbalanced force, the cell's deformation since `h0`.

namespace {

// YADE's Shop::unbalancedForce(useMaxForce=False) for a scene without gravity (the cell's
// specimens have none): mean |resultant force| over the dynamic bodies (clump members left out)
// over the mean |contact force| over the real interactions. Written here because Shop.hpp
// cannot be included (CMakeLists.txt); test_yade_plugin.py compares it with utils.unbalancedForce().
Real unbalancedForce(Scene* scene) {
  scene->forces.sync();
  Real sumF = 0;
  long nb = 0;
  for (const auto& b : *scene->bodies) {
    if (!b || b->isClumpMember() || !b->isDynamic()) continue;
    sumF += scene->forces.getForce(b->id).norm();
    ++nb;
  }
  const Real meanF = sumF / nb;
  Real sumC = 0;
  long nc = 0;
  for (const auto& I : *scene->interactions) {
    if (!I->isReal()) continue;
    const auto* p = static_cast<const NormShearPhys*>(I->phys.get());
    sumC += (p->normalForce + p->shearForce).norm();
    ++nc;
  }
  return meanF / (sumC / nc);
}

ta::CellMeasurement measureCell(Scene* scene, const Matrix3r& h0) {
  ta::CellMeasurement m;
  ta::Mat3 stress = ta::Mat3::Zero();
  ta::Vec6 stiff = ta::Vec6::Zero();
  const Matrix3r& h = scene->cell->hSize;
  for (const auto& I : *scene->interactions) {
    if (!I->isReal()) continue;
    const auto* g = dynamic_cast<const ScGeom*>(I->geom.get());
    const auto* p = dynamic_cast<const NormShearPhys*>(I->phys.get());
    if (!g || !p) continue;
    if (!(p->normalForce.squaredNorm() > 0)) continue;
    const Vector3r L = Body::byId(I->getId2(), scene)->state->pos + h * I->cellDist.cast<Real>()
        - Body::byId(I->getId1(), scene)->state->pos;
    ta::addStressTerm(p->normalForce + p->shearForce, L, stress);
    if (p->kn > 0) {
      const auto* sp = dynamic_cast<const SimplifiedMindlinPhys*>(p);
      ta::addAffineStiffnessTerm(p->kn, sp ? sp->stiffnessRatio : p->ks / p->kn, g->normal, L, stiff);
    }
  }
  const Real V = h.determinant();
  m.stress = ta::voigt::fromTensor(stress / V);
  m.stiffness = stiff / V;
  m.deformation = h * h0.inverse();
  const Real u = unbalancedForce(scene);
  m.unbalanced = std::isfinite(u) ? u : 1.0;
  return m;
}

void setFriction(Scene* scene, Real mu) {
  for (const auto& I : *scene->interactions)
    if (auto* p = dynamic_cast<FrictPhys*>(I->phys.get())) p->tangensOfFrictionAngle = mu;
}

void stopNextStep(Scene* scene) { scene->stopAtIter = scene->iter + 1; }

}  // namespace

// ---------------------------------------------------------------------------------------------
// TrueTriaxialServo: control/TrueTriaxialServo.hpp on O.cell.velGrad.

class TrueTriaxialServo : public GlobalEngine {
 public:
  void action() override {
    if (!scene->isPeriodic) throw std::runtime_error("TrueTriaxialServo needs a periodic cell (O.periodic=True)");
    if (reached || failed) return;
    ta::TrueTriaxialServo k = kernel();
    if (status == 0) {  // first call: the cell's reference and the loading friction
      hSize0 = scene->cell->hSize;
      setFriction(scene, loadingFriction);
    }
    const ta::Vec6 rates = k.update(measureCell(scene, hSize0), scene->dt);
    store(k);
    scene->cell->setVelGrad(ta::CellServoLaw::velocityGradient(rates));
    if ((reached || failed) && pauseWhenDone) stopNextStep(scene);
  }
  // Our servo with this engine's parameters and state.
  ta::TrueTriaxialServo kernel() const {
    ta::TrueTriaxialServo k;
    k.goal.b = b;
    k.goal.sigmaZ = sigmaZ;
    k.goal.p = meanStress;
    k.law.gain = gain;
    k.law.maxStrainRate = maxStrainRate;
    k.loadingFriction = loadingFriction;
    k.pathRate = pathRate;
    k.followTolerance = followTolerance;
    k.stressTolerance = stressTolerance;
    k.unbalancedTolerance = unbalancedTolerance;
    k.settleSteps = settleSteps;
    k.maxStrain = maxStrain;
    k.maxSteps = maxSteps;
    k.status = static_cast<ta::TrueTriaxialServo::Status>(status);
    k.progress = progress;
    k.startStress = toVec6(startStress);
    k.target = toVec6(target);
    k.startDeformation = startDeformation;
    k.overshoot = toVec6(overshoot);
    k.steps = steps;
    k.settled = settled;
    k.stalled = stalled;
    k.holding = holding;
    return k;
  }
  void store(const ta::TrueTriaxialServo& k) {
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
    unbalanced = k.unbalanced;
    stressError = k.gap.error();
    message = k.message;
    reached = k.status == ta::TrueTriaxialServo::Status::Reached;
    failed = k.status == ta::TrueTriaxialServo::Status::Failed;
  }
  ta::Vec6 finalStress() const { return kernel().finalStress(); }
  // clang-format off
  YADE_CLASS_BASE_DOC_ATTRS_CTOR_PY(TrueTriaxialServo, GlobalEngine,
    "The paper's b-controlled true-triaxial servo at constant mean stress (section 2.2, Eqs. 8-9), the code of the "
    "trueaniso engines (control/TrueTriaxialServo.hpp): it moves its goal from the stresses it finds along the straight "
    "path to the state (b, sigmaZ, meanStress), as fast as the specimen follows, holds the three shear stresses at zero "
    "on the full 3x3 cell, and sets :yref:`Cell.velGrad` every step. ``reached`` turns true when every stress is within "
    "stressTolerance and the unbalanced force below unbalancedTolerance for settleSteps steps in a row. Put it after "
    "InteractionLoop and before NewtonIntegrator. Stresses are compression positive, in Pa.",
    ((Real, b, 0, , "intermediate principal stress coefficient of Eq. (8)"))
    ((Real, sigmaZ, 100e3, , "sigma_z of the state [Pa]"))
    ((Real, meanStress, 100e3, , "mean stress p, constant along the path [Pa]"))
    ((Real, pathRate, 2.0, , "fastest motion of the goal along the path [Pa per step]"))
    ((Real, followTolerance, 1000.0, , "the goal advances while every stress is within this of it [Pa]"))
    ((Real, stressTolerance, 500.0, , "a state is held when every stress (shear too) is within this [Pa]"))
    ((Real, unbalancedTolerance, 1e-4, , "and YADE's unbalanced force below this"))
    ((long, settleSteps, 200, , "for this many steps in a row"))
    ((Real, maxStrain, 0.05, , "the specimen fails when a cell strain exceeds this"))
    ((long, maxSteps, 3000000, , "the servo fails after this many steps"))
    ((Real, gain, 0.01, , "fraction of the stress error closed per step"))
    ((Real, maxStrainRate, 1.0, , "largest cell strain rate [1/s]"))
    ((Real, loadingFriction, 0.5, , "friction coefficient set on every contact when the servo starts"))
    ((bool, pauseWhenDone, true, , "stop O.run after the step where the state is reached or fails"))
    ((bool, reached, false, Attr::readonly, "the state is held within tolerance"))
    ((bool, failed, false, Attr::readonly, "the specimen could not carry the state (see message)"))
    ((string, message, "", Attr::readonly, "why it failed"))
    ((Real, progress, 0, Attr::readonly, "0 at the start stresses, 1 at the state"))
    ((Vector6r, stress, Vector6r::Zero(), Attr::readonly, "last measured stress (Voigt xx yy zz yz xz xy) [Pa]"))
    ((Real, stressError, 0, Attr::readonly, "largest stress error against the state [Pa]"))
    ((Real, unbalanced, 0, Attr::readonly, "last unbalanced force"))
    ((int, status, 0, Attr::readonly, "0 idle, 1 loading, 2 holding, 3 reached, 4 failed"))
    ((Vector6r, startStress, Vector6r::Zero(), Attr::readonly, "stresses when the servo started"))
    ((Vector6r, target, Vector6r::Zero(), Attr::readonly, "current goal on the path"))
    ((Matrix3r, startDeformation, Matrix3r::Identity(), Attr::readonly, "cell deformation when the servo started"))
    ((Matrix3r, hSize0, Matrix3r::Identity(), Attr::readonly, "the cell when the servo started"))
    ((Vector6r, overshoot, Vector6r::Constant(-1e300), Attr::readonly, "largest excursion of each stress beyond its goal"))
    ((long, steps, 0, Attr::readonly, "steps run"))
    ((long, settled, 0, Attr::readonly, "steps in a row within tolerance"))
    ((long, stalled, 0, Attr::readonly, "steps in a row without following the goal"))
    ((long, holding, 0, Attr::readonly, "steps held at the state")),
    ,
    .def("finalStress", &TrueTriaxialServo::finalStressPy, "the six stresses of the state (Eq. 9), Voigt, Pa")
  );
  // clang-format on
  Vector6r finalStressPy() const { return fromVec6(finalStress()); }
};
REGISTER_SERIALIZABLE(TrueTriaxialServo);

// ---------------------------------------------------------------------------------------------
// StressProbe: control/StressProbe.hpp on O.cell.velGrad, with the snapshot and restore that our
// scene's probe does itself done here on YADE's scene.

class StressProbe : public GlobalEngine {
  std::unique_ptr<ta::StressProbe> k_;

  static int axisIndex(const std::string& a) {
    static const char* names[6] = {"x", "y", "z", "yz", "xz", "xy"};
    for (int k = 0; k < 6; ++k)
      if (a == names[k]) return k;
    throw std::invalid_argument("StressProbe.axis must be one of x, y, z, yz, xz, xy (got '" + a + "')");
  }

  // The held state lives in (hidden) attributes, so that O.save mid-probe keeps it: a probe loaded
  // mid-probe puts it back and probes again from it, as if never interrupted.
  void snapshot() {
    const std::size_t nb = scene->bodies->size();
    heldPos.assign(nb, Vector3r::Zero()); heldVel.assign(nb, Vector3r::Zero());
    heldAngVel.assign(nb, Vector3r::Zero()); heldOri.assign(nb, Quaternionr::Identity());
    heldBlocked.assign(nb, 0);
    for (std::size_t i = 0; i < nb; ++i) {
      const auto& b = (*scene->bodies)[i];
      if (!b) continue;
      const State& st = *b->state;
      heldPos[i] = st.pos; heldVel[i] = st.vel; heldAngVel[i] = st.angVel; heldOri[i] = st.ori;
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
      heldId1.push_back(I->getId1()); heldId2.push_back(I->getId2());
      heldNormalForce.push_back(p->normalForce); heldShearForce.push_back(p->shearForce);
      heldPrevNormal.push_back(sp ? sp->prevNormal : Vector3r::Zero());
      heldRollingMoment.push_back(sp ? sp->rollingMoment : Vector3r::Zero());
      heldGeomNormal.push_back(g->normal);
      heldMu.push_back(p->tangensOfFrictionAngle); heldDelta.push_back(g->penetrationDepth);
      heldLoaded.push_back(sp && sp->loaded ? 1 : 0);
    }
    heldHSize = scene->cell->hSize;
    heldTrsf = scene->cell->trsf;
    heldPrevHSize = scene->cell->prevHSize;
  }

  void clearHeld() {
    for (auto* v : {&heldPos, &heldVel, &heldAngVel, &heldNormalForce, &heldShearForce, &heldPrevNormal,
                    &heldRollingMoment, &heldGeomNormal})
      v->clear();
    for (auto* v : {&heldBlocked, &heldId1, &heldId2, &heldLoaded}) v->clear();
    heldOri.clear(); heldMu.clear(); heldDelta.clear();
  }

  void restore() {
    for (std::size_t i = 0; i < heldPos.size() && i < scene->bodies->size(); ++i) {
      const auto& b = (*scene->bodies)[i];
      if (!b) continue;
      State& st = *b->state;
      st.pos = heldPos[i]; st.vel = heldVel[i]; st.angVel = heldAngVel[i]; st.ori = heldOri[i];
      st.blockedDOFs = static_cast<unsigned>(heldBlocked[i]);
    }
    lostContacts = 0;
    for (std::size_t c = 0; c < heldId1.size(); ++c) {
      const shared_ptr<Interaction> I = scene->interactions->find(heldId1[c], heldId2[c]);
      if (!I || !I->isReal()) { ++lostContacts; continue; }
      auto* g = dynamic_cast<ScGeom*>(I->geom.get());
      auto* p = dynamic_cast<FrictPhys*>(I->phys.get());
      if (!g || !p) { ++lostContacts; continue; }
      p->normalForce = heldNormalForce[c]; p->shearForce = heldShearForce[c]; p->tangensOfFrictionAngle = heldMu[c];
      g->normal = heldGeomNormal[c]; g->penetrationDepth = heldDelta[c];
      if (auto* sp = dynamic_cast<SimplifiedMindlinPhys*>(p)) {
        sp->prevNormal = heldPrevNormal[c]; sp->rollingMoment = heldRollingMoment[c]; sp->loaded = heldLoaded[c] != 0;
      }
    }
    Cell& cell = *scene->cell;
    cell.hSize = heldHSize;
    cell.trsf = heldTrsf;
    cell.prevHSize = heldPrevHSize;
    cell.setVelGrad(Matrix3r::Zero());
    cell.velGrad = cell.prevVelGrad = Matrix3r::Zero();
    cell.integrateAndUpdate(0);
  }

 public:
  void action() override {
    if (!scene->isPeriodic) throw std::runtime_error("StressProbe needs a periodic cell (O.periodic=True)");
    if (finished) return;
    if (!k_ && stage >= 1 && stage <= 3 && !heldPos.empty()) restore();  // loaded mid-probe: from the held state
    if (!k_) {
      k_.reset(new ta::StressProbe());
      ta::StressProbe& k = *k_;
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
      hSize0 = scene->cell->hSize;
      const ta::CellMeasurement m0 = measureCell(scene, hSize0);
      ta::Vec6 hold = toVec6(holdStress);
      if (!hold.allFinite()) hold = m0.stress;
      holdStress = fromVec6(hold);
      snapshot();
      setFriction(scene, probeFriction);
      if (restrainRotations)
        for (const auto& b : *scene->bodies)
          if (b) { b->state->blockedDOFs |= State::DOF_RXRYRZ; b->state->angVel = Vector3r::Zero(); }
      k.begin(hold);
    }
    ta::StressProbe& k = *k_;
    const ta::Vec6 rates = k.update(measureCell(scene, hSize0), scene->dt);
    steps = k.steps;
    stage = static_cast<int>(k.stage);
    gamma = k.gamma;
    if (k.stage == ta::StressProbe::Stage::Done || k.stage == ta::StressProbe::Stage::Failed) {
      dStress = fromVec6(k.dStress);
      dStrain = fromVec6(k.dStrain);
      message = k.message;
      if (k.stage == ta::StressProbe::Stage::Done) {
        if (k.shearProbe()) {
          G = k.modulus();
        } else {
          E = k.youngModulus();
          for (int j = 0; j < 3; ++j) nu[j] = j == k.axis ? kNaN : k.poissonRatio(j);
        }
      }
      if (restoreState) restore();
      else scene->cell->setVelGrad(Matrix3r::Zero());
      clearHeld();  // a scene saved after the probe need not carry it
      finished = true;
      k_.reset();
      if (pauseWhenDone) stopNextStep(scene);
      return;
    }
    scene->cell->setVelGrad(ta::CellServoLaw::velocityGradient(rates));
  }
  // clang-format off
  YADE_CLASS_BASE_DOC_ATTRS_CTOR_PY(StressProbe, GlobalEngine,
    "The paper's directional stress probe (section 2.2, Eqs. 10-12), the code of the trueaniso engines "
    "(control/StressProbe.hpp): from the held state it suppresses sliding (friction probeFriction), optionally "
    "restrains rotations, relaxes, raises the stress on ``axis`` while the five others are held until gamma of "
    "Eq. (12) reaches gammaTarget, holds to equilibrium; then E (Eq. 10) and nu (Eq. 11), or G for a shear axis, "
    "and the scene is put back as it was (positions, velocities, cell, contact forces, friction). Put it after "
    "InteractionLoop and before NewtonIntegrator, alone on the cell (no servo active). A scene saved mid-probe "
    "keeps the held state: loaded, the probe puts it back and probes again from it.",
    ((string, axis, "z", , "x, y, z (E, nu) or yz, xz, xy (G)"))
    ((int, sign, 1, , "+1 loads (compression or positive shear), -1 unloads"))
    ((Real, gammaTarget, 1e-6, , "strain at which the ramp stops: gamma of Eq. (12), or the shear strain"))
    ((Real, increment, 0, , "> 0: a fixed stress increment [Pa] instead of gammaTarget"))
    ((Real, probeFriction, ta::kProbeFriction, , "friction during the probe (the paper's sliding suppressed)"))
    ((bool, restrainRotations, false, , "block particle rotations during the probe"))
    ((Vector6r, holdStress, Vector6r::Constant(kNaN), , "stresses held (Voigt, compression positive, Pa); NaN: those measured at the start"))
    ((Real, gain, 0.03, , "fraction of the stress error closed per step"))
    ((Real, maxStrainRate, 10.0, , "largest cell strain rate [1/s]; it only acts while relaxing, probes move strains of ~1e-6"))
    ((long, rampSteps, 300, , "expected length of the ramp (sets its rate)"))
    ((Real, relativeTolerance, 2e-3, , "stress error allowed, as a fraction of the increment"))
    ((Real, unbalancedTolerance, 1e-5, , "unbalanced force of the equilibrium"))
    ((long, settleSteps, 100, , "criteria met this many steps in a row"))
    ((long, maxSteps, 2000000, , "the probe fails after this many steps"))
    ((bool, restoreState, true, , "put the scene back when done"))
    ((bool, pauseWhenDone, true, , "stop O.run after the step where the probe ends"))
    ((bool, finished, false, Attr::readonly, "the probe has ended (see E, nu, G or message)"))
    ((Real, E, kNaN, Attr::readonly, "Young's modulus of axis, Eq. (10) [Pa]"))
    ((Vector3r, nu, Vector3r::Constant(kNaN), Attr::readonly, "Poisson's ratios nu_ij = -d eps_j / d eps_i, Eq. (11), for j = x, y, z (NaN at i)"))
    ((Real, G, kNaN, Attr::readonly, "shear modulus of a shear axis [Pa]"))
    ((Vector6r, dStress, Vector6r::Zero(), Attr::readonly, "stress increments (Voigt) [Pa]"))
    ((Vector6r, dStrain, Vector6r::Zero(), Attr::readonly, "strain increments (Voigt, engineering shear, compression positive)"))
    ((Real, gamma, 0, Attr::readonly, "current gamma"))
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
    ((Matrix3r, heldPrevHSize, Matrix3r::Identity(), Attr::hidden, "held state: cell prevHSize")),
    ,
    .def("reset", &StressProbe::resetPy, "forget the results and probe again at the next step")
  );
  // clang-format on
  void resetPy() {
    clearHeld();
    finished = false;
    k_.reset();
    E = G = kNaN;
    nu = Vector3r::Constant(kNaN);
    stage = 0;
  }
};
REGISTER_SERIALIZABLE(StressProbe);

// ---------------------------------------------------------------------------------------------
// FabricRecorder: the fabric of measure/Fabric.hpp from YADE's interactions.

class FabricRecorder : public PeriodicEngine {
 public:
  void action() override {
    ta::FabricSums sum;
    const Matrix3r& h = scene->cell->hSize;
    std::vector<int> perBody(scene->bodies->size(), 0);
    for (const auto& I : *scene->interactions) {
      if (!I->isReal()) continue;
      const auto* g = dynamic_cast<const ScGeom*>(I->geom.get());
      const auto* p = dynamic_cast<const NormShearPhys*>(I->phys.get());
      if (!g || !p) continue;
      const Real N = p->normalForce.norm();
      if (!(N > 0)) continue;
      const Vector3r L = Body::byId(I->getId2(), scene)->state->pos
          + (scene->isPeriodic ? Vector3r(h * I->cellDist.cast<Real>()) : Vector3r::Zero())
          - Body::byId(I->getId1(), scene)->state->pos;
      const Real rbar = 2.0 * g->radius1 * g->radius2 / (g->radius1 + g->radius2);
      sum.add(N, rbar, g->normal, L);
      ++perBody[I->getId1()];
      ++perBody[I->getId2()];
    }
    ta::Fabric f;
    Real solid = 0;
    long nb = 0;
    for (const auto& b : *scene->bodies) {
      if (!b) continue;
      const auto* s = dynamic_cast<const Sphere*>(b->shape.get());
      if (!s) continue;
      ++nb;
      solid += 4.0 / 3.0 * M_PI * s->radius * s->radius * s->radius;
      const int k = perBody[b->getId()];
      if (k == 0) ++f.counts.noContact;
      if (k == 1) ++f.counts.oneContact;
    }
    f.counts.particles = nb;
    sum.finish(f);
    Zm = f.counts.mechanical();
    R = f.R;
    H = f.H;
    B = f.B;
    M.assign(f.M.data(), f.M.data() + 81);  // symmetric: row or column order alike
    contacts = sum.contacts;
    particles = nb;
    volume = scene->isPeriodic ? h.determinant() : kNaN;
    NcOverV = contacts / volume;
    voidRatio = (volume - solid) / solid;
    meanNormalForce = f.meanNormalForce;
    records += 1;
  }
  // clang-format off
  YADE_CLASS_BASE_DOC_ATTRS(FabricRecorder, PeriodicEngine,
    "The fabric of the contact network (paper sections 3.2 and 4.2), the code of the trueaniso engines "
    "(measure/Fabric.hpp), every iterPeriod steps: Zm (Eq. 14), R (Eq. 15), H (Eq. 16), B (Eq. 33), M (Eq. 34, "
    "81 values M[9(3i+j)+3k+l]), the contact density Nc/V and the void ratio, over the contacts carrying a normal "
    "force. Spheres only. Put it after InteractionLoop.",
    ((Real, Zm, kNaN, Attr::readonly, "mechanical coordination number, Eq. (14)"))
    ((Matrix3r, R, Matrix3r::Zero(), Attr::readonly, "contact normal fabric, Eq. (15)"))
    ((Matrix3r, H, Matrix3r::Zero(), Attr::readonly, "branch vector fabric, Eq. (16) [m^2]"))
    ((Matrix3r, B, Matrix3r::Zero(), Attr::readonly, "branch-contact-stiffness fabric, Eq. (33)"))
    ((vector<Real>, M, , Attr::readonly, "mixed fourth-order tensor of Eq. (34), 81 values in C order"))
    ((Real, NcOverV, kNaN, Attr::readonly, "contacts per volume, counted [1/m^3]"))
    ((Real, voidRatio, kNaN, Attr::readonly, "void ratio from the spheres' volumes"))
    ((Real, meanNormalForce, kNaN, Attr::readonly, "mean normal force over the contacts [N]"))
    ((Real, volume, kNaN, Attr::readonly, "cell volume [m^3]"))
    ((long, contacts, 0, Attr::readonly, "Nc"))
    ((long, particles, 0, Attr::readonly, "Np (spheres)"))
    ((long, records, 0, Attr::readonly, "times recorded")));
  // clang-format on
};
REGISTER_SERIALIZABLE(FabricRecorder);

YADE_PLUGIN((SimplifiedMindlinPhys)(Ip2_FrictMat_FrictMat_SimplifiedMindlinPhys)(Law2_ScGeom_SimplifiedMindlinPhys_Mindlin)
            (TrueanisoAbiCheck)(TrueTriaxialServo)(StressProbe)(FabricRecorder));

}  // namespace yade
