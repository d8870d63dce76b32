#pragma once
// What the plugin's engines read of YADE's scene, with the particles of the paper: a clump is one
// particle (its members' contacts are its contacts, its centre the end of their branch vectors),
// a free sphere another. Included by TrueanisoYade.cpp after YADE's headers and our kernels.
//
// YADE never wraps a body into the periodic cell, and moves a clump's members with the clump, so a
// member and its clump lie in the same image: the branch of a contact between members of two clumps
// is clump 2 + hSize cellDist - clump 1, cellDist being the interaction's (YADE's getStress takes
// the same). The measurement is our stepper's (control/CellMeasurement, measure/ContactTerms):
// Love-Weber stress and affine stiffness summed over the contacts with those branches, YADE's
// unbalanced force with a clump's force summed from its members.
#include <core/Clump.hpp>
#include <core/Scene.hpp>
#include <pkg/common/Sphere.hpp>
#include <pkg/dem/FrictPhys.hpp>
#include <pkg/dem/ScGeom.hpp>

#include <cmath>
#include <string>

#include "YadeRefusal.hpp"

namespace yade {
namespace trueanisoPlugin {

namespace ta = trueaniso;

// The particle a body belongs to: its clump for a clump member, else the body itself.
inline const Body* particleOf(const Body* b, const Scene* scene) {
  return b->isClumpMember() ? Body::byId(b->clumpId, const_cast<Scene*>(scene)).get() : b;
}

// Branch vector of a contact, from the particle of body 1 to the particle of body 2's image.
inline Vector3r branchOf(const Interaction& I, const Scene* scene) {
  Scene* s = const_cast<Scene*>(scene);
  const Body* p1 = particleOf(Body::byId(I.getId1(), s).get(), scene);
  const Body* p2 = particleOf(Body::byId(I.getId2(), s).get(), scene);
  Vector3r L = p2->state->pos - p1->state->pos;
  if (scene->isPeriodic) L += scene->cell->hSize * I.cellDist.cast<Real>();
  return L;
}

// YADE's Shop::unbalancedForce(useMaxForce=False) for a scene without gravity (the cell's
// specimens have none): mean |resultant force| over the dynamic particles over the mean
// |contact force| over the real interactions. A clump's force is its members' sum: before
// NewtonIntegrator, where our engines run, YADE has not yet gathered it onto the clump (Shop does
// the same sum then). Written here because Shop.hpp cannot be included (CMakeLists.txt);
// test_yade_plugin.py compares it with utils.unbalancedForce().
inline Real unbalancedForce(Scene* scene) {
  scene->forces.sync();
  Real sumF = 0;
  long nb = 0;
  for (const auto& b : *scene->bodies) {
    if (!b || b->isClumpMember() || !b->isDynamic()) continue;
    Vector3r f = scene->forces.getForce(b->id);
    if (b->isClump())
      for (const auto& m : YADE_CAST<Clump*>(b->shape.get())->members) f += scene->forces.getForce(m.first);
    sumF += f.norm();
    ++nb;
  }
  Real sumC = 0;
  long nc = 0;
  for (const auto& I : *scene->interactions) {
    if (!I->isReal()) continue;
    const auto* p = dynamic_cast<const NormShearPhys*>(I->phys.get());
    if (!p) continue;
    sumC += (p->normalForce + p->shearForce).norm();
    ++nc;
  }
  return (sumF / nb) / (sumC / nc);
}

// k_s/k_n of a contact for the affine stiffness: the law's own ratio for our phys, YADE's ks/kn for another.
template <class Phys> Real stiffnessRatio(const NormShearPhys* p) {
  const auto* ours = dynamic_cast<const Phys*>(p);
  return ours ? ours->stiffnessRatio : p->ks / p->kn;
}

// The cell measurement of control/CellMeasurement on YADE's scene, strains counted from h0.
template <class Phys> ta::CellMeasurement measureCell(Scene* scene, const Matrix3r& h0) {
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
    const Vector3r L = branchOf(*I, scene);
    ta::addStressTerm(p->normalForce + p->shearForce, L, stress);
    if (p->kn > 0) ta::addAffineStiffnessTerm(p->kn, stiffnessRatio<Phys>(p), g->normal, L, stiff);
  }
  const Real V = h.determinant();
  m.stress = ta::voigt::fromTensor(stress / V);
  m.stiffness = stiff / V;
  m.deformation = h * h0.inverse();
  const Real u = unbalancedForce(scene);
  m.unbalanced = std::isfinite(u) ? u : 1.0;
  return m;
}

// The friction coefficient of every contact (a controller's, each step: the contacts YADE makes
// meanwhile get their materials' friction from the Ip2, and take the controller's at the next step).
inline void setFriction(Scene* scene, Real mu) {
  for (const auto& I : *scene->interactions)
    if (auto* p = dynamic_cast<FrictPhys*>(I->phys.get())) p->tangensOfFrictionAngle = mu;
}

// A second active controller of the cell beside `self`, as "ClassName 'label'" (empty: none):
// ours when not done (a servo that has reached or failed its state, a finished probe, are not
// active), YADE's cell controllers when not dead.
template <class Servo, class Probe> std::string otherCellController(Scene* scene, const Engine* self) {
  for (const auto& e : scene->engines) {
    if (!e || e.get() == self || e->dead) continue;
    const std::string cls = e->getClassName();
    bool active = false;
    if (const auto* s = dynamic_cast<const Servo*>(e.get())) active = !(s->reached || s->failed);
    else if (const auto* p = dynamic_cast<const Probe*>(e.get())) active = !p->finished;
    else active = cls == "PeriTriaxController" || cls == "PeriIsoCompressor" || cls == "Peri3dController";
    if (active) return cls + (e->label.empty() ? std::string() : " '" + e->label + "'");
  }
  return std::string();
}

inline void stopNextStep(Scene* scene) { scene->stopAtIter = scene->iter + 1; }

}  // namespace trueanisoPlugin
}  // namespace yade
