#pragma once
// The contact law of the paper (Eqs. 5-7) as YADE classes: the phys a contact carries, the Ip2
// that makes it from two FrictMat, the Law2 that evaluates it (contact/HertzMindlin.hpp). Included
// by TrueanisoYade.cpp after YADE's headers and our kernels.
//
// Both functors run inside YADE's parallel interaction loop, where an exception would end the
// process: what they cannot evaluate (a material out of range, a geometry the law is not for)
// gives the contact no force and is handed to YADE's loop (YadeRefusal.hpp: stopLoopWith), which
// stops after the step and raises it in Python.
#include <core/Dispatching.hpp>
#include <pkg/common/Box.hpp>
#include <pkg/common/ElastMat.hpp>
#include <pkg/common/Facet.hpp>
#include <pkg/common/Sphere.hpp>
#include <pkg/common/Wall.hpp>
#include <pkg/dem/FrictPhys.hpp>
#include <pkg/dem/ScGeom.hpp>

#include <cmath>
#include <set>
#include <string>

#include "PythonAttributes.hpp"
#include "YadeRefusal.hpp"

namespace yade {

class SimplifiedMindlinPhys : public FrictPhys {
 public:
  trueaniso::HertzMindlin law() const {
    return trueaniso::HertzMindlin(trueaniso::HertzMindlin::Constants{stiffnessRatio, tangensOfFrictionAngle, Cn, Cs,
                                                                      hertzUnit, rollingStiffness, rollingFriction});
  }
  virtual ~SimplifiedMindlinPhys() = default;
  // clang-format off
  YADE_CLASS_BASE_DOC_ATTRS_CTOR(SimplifiedMindlinPhys, FrictPhys,
    "The paper's simplified Hertz-Mindlin contact (Eqs. 5-7) of the trueaniso engines: Hertz's normal force, "
    "the tangential stiffness $k_s = (C_s/C_n)\\,k_n$ of Eq. (6) carried with the contact frame by an exact rotation, "
    "Coulomb's cap at tangensOfFrictionAngle times $N$ (1e23 suppresses sliding, as StressProbe does), an optional "
    "rolling spring. Made by :yref:`Ip2_FrictMat_FrictMat_SimplifiedMindlinPhys`. Forces in N, on body 2 "
    "(normalForce along the normal from body 1 to body 2: a compressed contact's normalForce points from 1 to 2).",
    ((Real, rbar, 0, , "$\\bar r$ of Eq. (7), $2 r_1 r_2/(r_1 + r_2)$ between two spheres, $2r$ for a sphere on a wall, facet or box [m]"))
    ((Real, hertzUnit, 0, , "$(4/3) E^* \\sqrt{1/2}$, so that $N = \\text{hertzUnit}\\,\\sqrt{\\bar r}\\,\\delta^{3/2}$ [Pa]"))
    ((Real, stiffnessRatio, 0, , "$k_s/k_n = C_s/C_n$: $2(1-\\nu)/(2-\\nu)$ for one material, $4 G^*/E^*$ for two"))
    ((Real, Cn, 0, , "$C_n$ of Eq. (5): $k_n = C_n (\\bar r N)^{1/3}$ [$\\mathrm{Pa}^{2/3}$]"))
    ((Real, Cs, 0, , "$C_s$ of Eq. (6): $k_s = C_s (\\bar r N)^{1/3}$ [$\\mathrm{Pa}^{2/3}$]"))
    ((Real, rollingStiffness, 0, , "$\\beta$ of the rolling spring $k_r = \\beta k_s \\bar r^2$ (0: no rolling resistance)"))
    ((Real, rollingFriction, 0, , "$\\eta_r$: the rolling moment is capped at $\\eta_r \\bar r N$"))
    ((Vector3r, rollingMoment, Vector3r::Zero(), , "rolling moment on body 2 [N m]"))
    ((Vector3r, prevNormal, Vector3r::Zero(), , "the contact normal at the last evaluation"))
    ((bool, loaded, false, , "the contact carried a force at the last evaluation"))
    ((bool, isSliding, false, , "at the Coulomb cap after the last evaluation"))
    ((bool, refused, false, Attr::readonly, "the Ip2 could not make this contact's constants (the message was raised by O.run); it carries no force and is made again at each step")),
    createIndex());
  // clang-format on
  REGISTER_CLASS_INDEX(SimplifiedMindlinPhys, FrictPhys);
};
REGISTER_SERIALIZABLE(SimplifiedMindlinPhys);

class Ip2_FrictMat_FrictMat_SimplifiedMindlinPhys : public IPhysFunctor {
  // Our material from a FrictMat: G = young/(2(1+poisson)), nu = poisson, mu = tan(frictionAngle),
  // checked by Material::validate (and young, frictionAngle finite).
  trueaniso::Material material(const FrictMat& f) const {
    trueaniso::Material m;
    m.poisson = f.poisson;
    m.shearModulus = f.young / (2.0 * (1.0 + f.poisson));
    m.friction = std::tan(f.frictionAngle);
    m.rollingStiffness = rollingStiffness;
    m.rollingFriction = rollingFriction;
    const std::string what = "FrictMat" + (f.label.empty() ? std::string() : " '" + f.label + "'") + " (young " +
        trueanisoPlugin::shown(f.young) + ", poisson " + trueanisoPlugin::shown(f.poisson) + ", frictionAngle " +
        trueanisoPlugin::shown(f.frictionAngle) + ")";
    if (!(std::isfinite(f.young) && f.young > 0)) throw std::invalid_argument(what + ": young must be a finite number > 0");
    if (!(std::isfinite(f.frictionAngle) && f.frictionAngle >= 0 && f.frictionAngle <= M_PI / 2))
      throw std::invalid_argument(what + ": frictionAngle must lie in [0, pi/2]");
    try {
      m.validate();
    } catch (const std::exception& e) {
      throw std::invalid_argument(what + ": " + e.what());
    }
    return m;
  }

  // r-bar of Eq. (7) from the two bodies' shapes: two spheres (free or clump members), or a sphere
  // against a wall, facet or box, taken as a half-space (Hertz's R* = r, rbar = 2 r).
  Real rbarOf(const Interaction& I) const {
    const Body* b1 = Body::byId(I.getId1(), scene).get();
    const Body* b2 = Body::byId(I.getId2(), scene).get();
    // The classes themselves, not their subclasses: YADE's Cylinder and GridNode derive from Sphere.
    auto sphere = [](const Shape* s) {
      return s && s->getClassName() == "Sphere" ? static_cast<const Sphere*>(s) : nullptr;
    };
    auto plane = [](const Shape* s) {
      const std::string c = s ? s->getClassName() : std::string();
      return c == "Wall" || c == "Facet" || c == "Box";
    };
    const Sphere *s1 = sphere(b1->shape.get()), *s2 = sphere(b2->shape.get());
    if (s1 && s2) return 2.0 * s1->radius * s2->radius / (s1->radius + s2->radius);
    if (s1 && plane(b2->shape.get())) return 2.0 * s1->radius;
    if (s2 && plane(b1->shape.get())) return 2.0 * s2->radius;
    throw std::invalid_argument("contact of bodies #" + trueanisoPlugin::shown(b1->id) + " (" +
                                b1->shape->getClassName() + ") and #" + trueanisoPlugin::shown(b2->id) + " (" +
                                b2->shape->getClassName() +
                                "): the paper's law is for spheres, and a sphere against a Wall, Facet or Box");
  }

 public:
  void go(const shared_ptr<Material>& m1, const shared_ptr<Material>& m2, const shared_ptr<Interaction>& I) override {
    // A refused contact is tried again every step: the material may have been corrected since.
    if (I->phys) {
      const auto* made = dynamic_cast<const SimplifiedMindlinPhys*>(I->phys.get());
      if (!made || !made->refused) return;
    }
    auto p = shared_ptr<SimplifiedMindlinPhys>(new SimplifiedMindlinPhys());
    try {
      const trueaniso::HertzMindlin::Constants c =
          trueaniso::pairConstants(material(*YADE_CAST<FrictMat*>(m1.get())), material(*YADE_CAST<FrictMat*>(m2.get())));
      p->rbar = rbarOf(*I);
      p->hertzUnit = c.hertzUnit;
      p->stiffnessRatio = c.ratio;
      p->Cn = c.Cn;
      p->Cs = c.Cs;
      p->rollingStiffness = c.beta;
      p->rollingFriction = c.etaR;
      p->tangensOfFrictionAngle = c.mu;
    } catch (const std::exception& e) {
      p = shared_ptr<SimplifiedMindlinPhys>(new SimplifiedMindlinPhys());
      p->refused = true;
      trueanisoPlugin::stopLoopWith(scene, std::string("Ip2_FrictMat_FrictMat_SimplifiedMindlinPhys: ") + e.what());
    }
    I->phys = p;
  }
  // The rolling parameters in range; an assignment refused keeps the old value (PythonAttributes).
  void postLoad(Ip2_FrictMat_FrictMat_SimplifiedMindlinPhys&) {
    trueaniso::Material m;
    m.rollingStiffness = rollingStiffness;
    m.rollingFriction = rollingFriction;
    try {
      m.validate();
    } catch (const std::exception& e) {
      throw std::invalid_argument("Ip2_FrictMat_FrictMat_SimplifiedMindlinPhys (rollingStiffness " +
                                  trueanisoPlugin::shown(rollingStiffness) + ", rollingFriction " +
                                  trueanisoPlugin::shown(rollingFriction) + "): " + e.what());
    }
  }
  static std::set<std::string> customAttributes() { return {}; }
  void pyHandleCustomCtorArgs(boost::python::tuple& /*t*/, boost::python::dict& d) override {
    trueanisoPlugin::PythonAttributes<Ip2_FrictMat_FrictMat_SimplifiedMindlinPhys>::checkConstructorArguments(d);
  }
  FUNCTOR2D(FrictMat, FrictMat);
  // clang-format off
  YADE_CLASS_BASE_DOC_ATTRS_CTOR_PY(Ip2_FrictMat_FrictMat_SimplifiedMindlinPhys, IPhysFunctor,
    "Makes :yref:`SimplifiedMindlinPhys` from two FrictMat: each one's shear modulus $G = E/(2(1+\\nu))$ from its "
    "young $E$ and poisson $\\nu$ (the particle's Poisson ratio, as in :yref:`Ip2_FrictMat_FrictMat_MindlinPhys`), "
    "friction the tangent of the smaller frictionAngle. One material gives the paper's $C_n$ and $C_s$ (Eqs. 5-6); "
    "two give Hertz's and Mindlin's combined moduli, $1/E^* = \\sum_i (1-\\nu_i)/(2 G_i)$, "
    "$1/G^* = \\sum_i (2-\\nu_i)/G_i$, $k_s/k_n = 4 G^*/E^*$ (contact/MaterialPair.hpp). Contacts between two "
    "spheres (free or clump members) take $\\bar r$ of Eq. (7); a sphere against a Wall, Facet or Box is a sphere "
    "on a half-space ($\\bar r = 2r$). Refused with a RuntimeError from O.run (the contact carries no force, "
    "the run stops after the step): young or frictionAngle not finite, young <= 0, poisson outside (-1, 0.5), any "
    "other pair of shapes.",
    ((Real, rollingStiffness, 0, Attr::triggerPostLoad, "$\\beta$ of the rolling spring $k_r = \\beta k_s \\bar r^2$ (0: none; >= 0)"))
    ((Real, rollingFriction, 0, Attr::triggerPostLoad, "$\\eta_r$ of the rolling cap $\\eta_r \\bar r N$ (>= 0)")),
    /* ctor */,
    PYTHON_ATTRIBUTES_DEFS(Ip2_FrictMat_FrictMat_SimplifiedMindlinPhys));
  // clang-format on
};
REGISTER_SERIALIZABLE(Ip2_FrictMat_FrictMat_SimplifiedMindlinPhys);

class Law2_ScGeom_SimplifiedMindlinPhys_Mindlin : public LawFunctor {
 public:
  bool go(shared_ptr<IGeom>& ig, shared_ptr<IPhys>& ip, Interaction* I) override {
    auto* g = static_cast<ScGeom*>(ig.get());
    auto* p = static_cast<SimplifiedMindlinPhys*>(ip.get());
    const Real delta = g->penetrationDepth;
    if (delta < 0 || p->refused) {
      if (delta < 0 && !neverErase) return false;
      p->normalForce = p->shearForce = p->rollingMoment = Vector3r::Zero();
      p->kn = p->ks = 0;
      p->loaded = false;
      return true;
    }
    try {
      evaluate(*g, *p, *I);
    } catch (const std::exception& e) {  // nothing in the law throws today; never let one end the process
      p->normalForce = p->shearForce = p->rollingMoment = Vector3r::Zero();
      trueanisoPlugin::stopLoopWith(scene, std::string("Law2_ScGeom_SimplifiedMindlinPhys_Mindlin: ") + e.what());
    }
    return true;
  }
  FUNCTOR2D(ScGeom, SimplifiedMindlinPhys);
  // clang-format off
  YADE_CLASS_BASE_DOC_ATTRS(Law2_ScGeom_SimplifiedMindlinPhys_Mindlin, LawFunctor,
    "The paper's simplified Hertz-Mindlin law (Eqs. 5-7), the code of the trueaniso engines "
    "(contact/HertzMindlin.hpp): $N = (4/3) E^* \\sqrt{\\bar r/2}\\,\\delta^{3/2}$, the shear force carried with the "
    "contact frame by an exact rotation and incremented by $-k_s$ times the step's tangential displacement, capped "
    "at tangensOfFrictionAngle times $N$; the rolling spring when the phys has rollingStiffness > 0. Build the geometry with "
    "Ig2_Sphere_Sphere_ScGeom(avoidGranularRatcheting=False) (our tangential displacement; docs/yade-peer.md). "
    "Geometries: ScGeom of two spheres, or of a sphere and a Wall, Facet or Box (a half-space); the Ip2 refuses others.",
    ((bool, neverErase, false, , "keep interactions whose spheres separated (forces zero)")));
  // clang-format on

 private:
  void evaluate(ScGeom& g, SimplifiedMindlinPhys& p, Interaction& I) {
    const Real delta = g.penetrationDepth;
    const Body::id_t id1 = I.getId1(), id2 = I.getId2();
    const State* s1 = Body::byId(id1, scene)->state.get();
    const State* s2 = Body::byId(id2, scene)->state.get();
    const Real dt = scene->dt;
    const Vector3r& n = g.normal;
    // The pair's spin about the current normal, and the tangential relative displacement of the
    // step (YADE's kinematics, computed by Ig2 as for its own laws).
    const Real twist = 0.5 * dt * n.dot(s1->angVel + s2->angVel);
    const trueaniso::HertzMindlin law = p.law();
    const trueaniso::HertzMindlin::Response r =
        law.evaluate(delta, p.rbar, n, p.loaded, p.prevNormal, p.shearForce, g.shearIncrement(), twist);
    p.normalForce = r.N * n;
    p.shearForce = r.Fs;
    p.isSliding = r.sliding;
    p.kn = trueaniso::HertzMindlin::normalStiffness(r.N, delta);
    p.ks = law.shearStiffness(p.kn);
    const Vector3r prev = p.prevNormal;
    const bool wasLoaded = p.loaded;
    p.prevNormal = n;
    p.loaded = r.N > 0;
    const Vector3r force = -p.normalForce - p.shearForce;  // on body 1
    scene->forces.addForce(id1, force);
    scene->forces.addForce(id2, -force);
    scene->forces.addTorque(id1, (g.radius1 - 0.5 * delta) * n.cross(force));
    scene->forces.addTorque(id2, (g.radius2 - 0.5 * delta) * n.cross(force));
    if (p.rollingStiffness > 0) {
      const Vector3r dw = (s2->angVel - s1->angVel) * dt;
      bool capped = false;
      p.rollingMoment = law.rollingMoment(p.rbar, r.N, p.ks, n, wasLoaded, prev, p.rollingMoment,
                                          dw - n.dot(dw) * n, twist, capped);
      scene->forces.addTorque(id1, -p.rollingMoment);
      scene->forces.addTorque(id2, p.rollingMoment);
    }
  }
};
REGISTER_SERIALIZABLE(Law2_ScGeom_SimplifiedMindlinPhys_Mindlin);

}  // namespace yade
