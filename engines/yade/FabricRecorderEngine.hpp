#pragma once
// FabricRecorder: the fabric of measure/Fabric.hpp from YADE's interactions, with the paper's
// particles (a clump counts once). Included by TrueanisoYade.cpp.
#include <core/Clump.hpp>
#include <pkg/common/PeriodicEngines.hpp>
#include <pkg/common/Sphere.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include "PythonAttributes.hpp"
#include "YadeRefusal.hpp"
#include "YadeScene.hpp"

namespace yade {

class FabricRecorder : public PeriodicEngine {
  // The union volume of balls, from a cache of shapes scaled to their largest radius: CGAL's mesh
  // takes ~0.1 s a clump, and a packing holds a few shapes (replaceByClumps scales one template
  // to every sphere it replaces). The key, radii and centre distances over the largest radius in
  // the clump's member order (rounded at 1e-10), is the shape up to rotation and reflection.
  static Real unionVolume(const std::vector<trueaniso::Vec3>& centres, const std::vector<Real>& radii) {
    static std::mutex guard;
    static std::map<std::vector<long long>, Real> unit;
    const Real scale = *std::max_element(radii.begin(), radii.end());
    std::vector<long long> key;
    for (std::size_t i = 0; i < radii.size(); ++i) {
      key.push_back(std::llround(1e10 * radii[i] / scale));
      for (std::size_t j = i + 1; j < radii.size(); ++j) key.push_back(std::llround(1e10 * (centres[j] - centres[i]).norm() / scale));
    }
    std::lock_guard<std::mutex> lock(guard);
    auto found = unit.find(key);
    if (found == unit.end()) {
      std::vector<trueaniso::Vec3> c;
      std::vector<Real> r;
      for (std::size_t i = 0; i < radii.size(); ++i) {
        c.push_back((centres[i] - centres[0]) / scale);
        r.push_back(radii[i] / scale);
      }
      found = unit.emplace(key, trueaniso::unionOfBallsMoments(c, r).volume).first;
    }
    return found->second * scale * scale * scale;
  }

  // Solid volume of a particle (a clump's: the union of its member balls, overlaps counted once,
  // measure/Coordination's rule), from its radii as they are now: a YADE script may grow them
  // (utils.growParticles) or replace bodies between records; a clump's shape is cached by its key.
  static Real solidVolume(const Body& b, Scene* scene) {
    Real v = 0;
    if (const auto* s = dynamic_cast<const Sphere*>(b.shape.get())) {
      v = 4.0 / 3.0 * M_PI * s->radius * s->radius * s->radius;
    } else {
      std::vector<trueaniso::Vec3> centres;
      std::vector<Real> radii;
      for (const auto& m : YADE_CAST<const Clump*>(b.shape.get())->members) {
        const Shape* shape = Body::byId(m.first, scene)->shape.get();
        const auto* s = shape && shape->getClassName() == "Sphere" ? static_cast<const Sphere*>(shape) : nullptr;
        if (!s) throw std::runtime_error("FabricRecorder: clump #" + trueanisoPlugin::shown(b.id) + " has member #" +
                                         trueanisoPlugin::shown(m.first) + ", which is no sphere");
        centres.push_back(m.second.position);
        radii.push_back(s->radius);
      }
      v = unionVolume(centres, radii);
    }
    return v;
  }

 public:
  void action() override { trueanisoPlugin::refusingInLoop([&] { record(); }); }
  // Every step, not only those it records at: a scene it cannot measure is refused at the first.
  bool isActivated() override {
    trueanisoPlugin::refusingInLoop([&] { checkPeriodic(); });
    return PeriodicEngine::isActivated();
  }

  // The periods: one of them > 0, or the recorder would never record in O.engines.
  void postLoad(FabricRecorder&) {
    namespace tp = trueanisoPlugin;
    for (const auto& p : {std::make_pair("iterPeriod", Real(iterPeriod)), std::make_pair("virtPeriod", virtPeriod),
                          std::make_pair("realPeriod", realPeriod)})
      if (!(p.second >= 0)) tp::refuse("FabricRecorder", p.first, tp::shown(p.second), "a period is >= 0 (0: not used)");
    if (!(iterPeriod > 0 || virtPeriod > 0 || realPeriod > 0))
      tp::refuse("FabricRecorder", "iterPeriod", tp::shown(iterPeriod),
                 "with virtPeriod and realPeriod 0 too, it would never record: give iterPeriod > 0 (default 100, "
                 "about 1 % of the steps' time); to record only when called, call it (recorder()) outside O.engines");
  }
  static std::set<std::string> customAttributes() { return {}; }
  void pyHandleCustomCtorArgs(boost::python::tuple& /*t*/, boost::python::dict& d) override {
    trueanisoPlugin::PythonAttributes<FabricRecorder>::checkConstructorArguments(d);
  }

 private:
  void checkPeriodic() const {
    if (!scene->isPeriodic)
      throw std::runtime_error("FabricRecorder needs a periodic cell (O.periodic=True): its Nc/V and void ratio are "
                               "those of the cell, its branch vectors cross the cell's boundary");
  }

  void record() {
    namespace tp = trueanisoPlugin;
    checkPeriodic();
    // The particles: free spheres and clumps (of spheres); anything else is refused, not skipped.
    std::vector<int> perParticle(scene->bodies->size(), 0);
    long nb = 0;
    Real solid = 0;
    for (const auto& b : *scene->bodies) {
      if (!b || b->isClumpMember()) continue;
      if (!b->isClump() && !(b->shape && b->shape->getClassName() == "Sphere"))
        throw std::runtime_error("FabricRecorder counts spheres and clumps of spheres; body #" + tp::shown(b->id) +
                                 " is a " + (b->shape ? b->shape->getClassName() : std::string("body without shape")));
      ++nb;
      solid += solidVolume(*b, scene);
    }
    if (nb == 0)
      throw std::runtime_error("FabricRecorder: the scene has no particles (spheres or clumps of spheres): no fabric "
                               "and no void ratio to give");
    trueaniso::FabricSums sum;
    for (const auto& I : *scene->interactions) {
      if (!I->isReal()) continue;
      const auto* g = dynamic_cast<const ScGeom*>(I->geom.get());
      const auto* p = dynamic_cast<const NormShearPhys*>(I->phys.get());
      if (!g || !p) continue;
      const Real N = p->normalForce.norm();
      if (!(N > 0)) continue;
      const auto* ours = dynamic_cast<const SimplifiedMindlinPhys*>(p);
      const Real rbar = ours ? ours->rbar : 2.0 * g->radius1 * g->radius2 / (g->radius1 + g->radius2);
      sum.add(N, rbar, g->normal, tp::branchOf(*I, scene));
      ++perParticle[tp::particleOf(Body::byId(I->getId1(), scene).get(), scene)->id];
      ++perParticle[tp::particleOf(Body::byId(I->getId2(), scene).get(), scene)->id];
    }
    trueaniso::Fabric f;
    f.counts.particles = nb;
    for (const auto& b : *scene->bodies) {
      if (!b || b->isClumpMember()) continue;
      const int k = perParticle[b->id];
      if (k == 0) ++f.counts.noContact;
      if (k == 1) ++f.counts.oneContact;
    }
    sum.finish(f);
    f.Zm = f.counts.mechanical();
    f.volume = scene->cell->hSize.determinant();
    f.voidRatio = (f.volume - solid) / solid;
    f.meanRadiusCubed = 3.0 * solid / (4.0 * M_PI * nb);
    contacts = sum.contacts;
    particles = nb;
    rattlers = f.counts.noContact;
    oneContact = f.counts.oneContact;
    volume = f.volume;
    voidRatio = f.voidRatio;
    NcOverV = contacts / volume;
    if (contacts == 0) {
      message = "no contacts: no contact carries a normal force (a loose or unloaded packing); Zm is 0, R, H, B, M "
                "and the mean normal force 0";
      Zm = 0;
      R = H = B = Matrix3r::Zero();
      M.assign(81, 0.0);
      meanNormalForce = 0;
      NcOverVEq36 = 0;
    } else {
      message = std::isfinite(f.Zm) ? "" : "no particle has two contacts: Zm of Eq. (14) is undefined, given as 0";
      Zm = std::isfinite(f.Zm) ? f.Zm : 0.0;
      R = f.R;
      H = f.H;
      B = f.B;
      M.assign(f.M.data(), f.M.data() + 81);  // symmetric: row or column order alike
      meanNormalForce = f.meanNormalForce;
      NcOverVEq36 = std::isfinite(f.Zm) ? f.contactDensityEq36() : 0.0;
    }
    records += 1;
  }

 public:
  // clang-format off
  YADE_CLASS_BASE_DOC_ATTRS_CTOR_PY(FabricRecorder, PeriodicEngine,
    "The fabric of the contact network (paper sections 3.2 and 4.2), the code of the trueaniso engines "
    "(measure/Fabric.hpp, measure/FabricTerms.hpp), every iterPeriod steps (100 unless given: about 1 % of the "
    "steps' time) or by calling the engine: Zm (Eq. 14), R (Eq. 15), H (Eq. 16), B (Eq. 33), M (Eq. 34), the "
    "contact density $N_c/V$ counted and by Eq. (36), the void ratio, over the contacts carrying a normal force. Put "
    "it after InteractionLoop.\n\n"
    "Particles: free spheres and clumps of spheres; a clump is one particle (one Np, its members' contacts with "
    "other particles each count in $N_c$ and in its Zm), the branch vector $L$ joins particle centres (clump centres; "
    "the image of body 2 by the interaction's cellDist), $\\bar r$ (Eq. 7) is the two member spheres', and a clump's "
    "solid volume is the union of its balls, overlaps counted once. Any other body is refused.\n\n"
    "Units: R dimensionless, H $\\mathrm{m}^2$, B and M $\\mathrm{m}^{7/3}\\,\\mathrm{N}^{1/3}$ (the weight "
    "$(\\bar r N)^{1/3}$ of Eqs. 33-34 is $k_n/C_n$; the material constants $C_n$, $C_s$ stay outside), $N_c/V$ "
    "$\\mathrm{m}^{-3}$. M holds 81 values in C order: ``M[27*i + 9*j + 3*k + l]`` is $M_{ijkl}$.\n\n"
    "Refusals: a period < 0, or no period > 0 (it would never record), raises ValueError at construction or "
    "assignment; a value of the wrong type a TypeError naming the attribute. A scene that is not periodic raises "
    "RuntimeError from O.run at the first step, a scene without particles or a body other than a sphere or a clump "
    "of spheres at the first record. Without any contact carrying a force, ``message`` says 'no contacts' and the averages are 0 (not NaN); "
    "before the first record Zm is NaN and ``message`` 'not recorded yet'.",
    ((Real, Zm, NAN, Attr::readonly, "mechanical coordination number, Eq. (14): $Z_m = (2 N_c - N_p^1)/(N_p - N_p^0 - N_p^1)$"))
    ((Matrix3r, R, Matrix3r::Zero(), Attr::readonly, "contact normal fabric, Eq. (15): $R_{ij} = \\langle n_i n_j \\rangle$"))
    ((Matrix3r, H, Matrix3r::Zero(), Attr::readonly, "branch vector fabric, Eq. (16): $H_{ij} = \\langle L_i L_j \\rangle$ [$\\mathrm{m}^2$]"))
    ((Matrix3r, B, Matrix3r::Zero(), Attr::readonly, "branch-contact-stiffness fabric, Eq. (33): $B_{ij} = \\langle (\\bar r N)^{1/3} L_i L_j \\rangle$ [$\\mathrm{m}^{7/3}\\,\\mathrm{N}^{1/3}$]"))
    ((vector<Real>, M, , Attr::readonly, "mixed fourth-order tensor of Eq. (34): $M_{ijkl} = \\langle (\\bar r N)^{1/3} L_i n_j L_k n_l \\rangle$, 81 values in C order [$\\mathrm{m}^{7/3}\\,\\mathrm{N}^{1/3}$]"))
    ((Real, NcOverV, NAN, Attr::readonly, "contacts per volume, counted, $N_c/V$ [$\\mathrm{m}^{-3}$]"))
    ((Real, NcOverVEq36, NAN, Attr::readonly, "contacts per volume by Eq. (36), $3 Z_m/(8\\pi(1+e)\\langle r^3 \\rangle)$, a clump's $r^3$ from its volume [$\\mathrm{m}^{-3}$]"))
    ((Real, voidRatio, NAN, Attr::readonly, "void ratio $e = (V - V_s)/V_s$, $V_s$ the particles' solid volume"))
    ((Real, meanNormalForce, NAN, Attr::readonly, "mean normal force over the contacts [N]"))
    ((Real, volume, NAN, Attr::readonly, "cell volume $V$ [$\\mathrm{m}^3$]"))
    ((long, contacts, 0, Attr::readonly, "$N_c$: contacts carrying a normal force"))
    ((long, particles, 0, Attr::readonly, "$N_p$: free spheres and clumps"))
    ((long, rattlers, 0, Attr::readonly, "$N_p^0$: particles without a contact"))
    ((long, oneContact, 0, Attr::readonly, "$N_p^1$: particles with one contact"))
    ((long, records, 0, Attr::readonly, "times recorded"))
    ((string, message, "not recorded yet", Attr::readonly, "what the last record could not give ('no contacts', ...); empty when all is defined")),
    iterPeriod = 100;,
    PYTHON_ATTRIBUTES_DEFS(FabricRecorder));
  // clang-format on
};
REGISTER_SERIALIZABLE(FabricRecorder);

}  // namespace yade
