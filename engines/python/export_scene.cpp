// Scene, material and cell as seen from Python: arrays in, arrays out.
#include <algorithm>
#include <memory>
#include <numeric>

#include "contact/HertzMindlin.hpp"
#include "core/Scene.hpp"
#include "core/SpaceOrder.hpp"
#include "python/Numpy.hpp"

namespace trueaniso::py {

namespace {

using ScenePtr = std::shared_ptr<Scene>;

void addSpheres(Scene& s, const bp::object& pos, const bp::object& radii) {
  const std::vector<Vec3> p = toVec3List(pos, "positions");
  const std::vector<Real> r = toRealList(radii, "radii");
  require(p.size() == r.size(), "positions and radii must have the same length");
  for (Real x : r) require(x > 0 && std::isfinite(x), "every radius must be > 0");
  for (size_t i = 0; i < p.size(); ++i) s.addSphere(p[i], r[i]);
}

int addClump(Scene& s, const bp::object& pos, const bp::object& quat, const bp::object& offsets,
             const bp::object& radii, Real mass, const bp::object& inertia, Real volume) {
  const std::vector<Real> q = toRealList(quat, "orientation (w, x, y, z)");
  require(q.size() == 4, "orientation must be a quaternion (w, x, y, z)");
  return s.addClump(toVec3(pos, "position"), Quat(q[0], q[1], q[2], q[3]), toVec3List(offsets, "offsets"),
                    toRealList(radii, "radii"), mass, toVec3(inertia, "inertia"), volume);
}

np::ndarray orderInSpace(Scene& s) {
  const std::vector<int> order = spaceOrder(s);
  reorderBodies(s, order);
  return toNumpy(order);
}
void reorder(Scene& s, const bp::object& order) { reorderBodies(s, toIntList(order, "body order")); }

template <std::vector<Vec3> Bodies::*F>
np::ndarray getBodyVec(const Scene& s) { return toNumpy(s.bodies.*F); }
template <std::vector<Vec3> Bodies::*F>
void setBodyVec(Scene& s, const bp::object& o) {
  std::vector<Vec3> v = toVec3List(o, "body array");
  require(v.size() == s.bodies.pos.size(), "array length must equal the number of bodies");
  s.bodies.*F = std::move(v);
  if constexpr (F == &Bodies::pos) {
    s.refreshMembers();
    s.detectionInvalid = true;
  }
}

np::ndarray masses(const Scene& s) { return toNumpy(s.bodies.mass); }
np::ndarray inertia(const Scene& s) { return toNumpy(s.bodies.inertia); }
np::ndarray orientations(const Scene& s) {
  std::vector<Real> q;
  for (const Quat& o : s.bodies.orientation) { q.push_back(o.w()); q.push_back(o.x()); q.push_back(o.y()); q.push_back(o.z()); }
  np::ndarray a = toNumpy(q);
  return a.reshape(bp::make_tuple(s.bodies.size(), 4));
}
void setOrientations(Scene& s, const bp::object& o) {
  const std::vector<Real> q = toRealList(bp::import("numpy").attr("ravel")(o), "orientations");
  require(q.size() == 4 * s.bodies.orientation.size(), "orientations must have shape (n_bodies, 4)");
  for (size_t b = 0; b < s.bodies.orientation.size(); ++b)
    s.bodies.orientation[b] = unitQuaternion(Quat(q[4 * b], q[4 * b + 1], q[4 * b + 2], q[4 * b + 3]));
  s.refreshMembers();
  s.detectionInvalid = true;
}
np::ndarray memberBegin(const Scene& s) { return toNumpy(s.bodies.memberBegin); }
np::ndarray radii(const Scene& s) { return toNumpy(s.members.radius); }
void setRadii(Scene& s, const bp::object& o) {
  std::vector<Real> r = toRealList(o, "radii");
  require(r.size() == s.members.radius.size(), "radii length must equal the number of member spheres");
  require(!s.hasClumps(), "setting radii applies to single spheres; rebuild clumps instead");
  for (size_t b = 0; b < r.size(); ++b) s.setSphereRadius(static_cast<int>(b), r[b]);
  s.detectionInvalid = true;
}
np::ndarray memberBody(const Scene& s) { return toNumpy(s.members.body); }
np::ndarray memberOffsets(const Scene& s) { return toNumpy(s.members.offset); }
np::ndarray memberPositions(const Scene& s) { return toNumpy(s.members.pos); }

// The cell as YADE's: hSize (columns = cell vectors), its reference, the velocity gradient.
np::ndarray cellMatrix(const Scene& s) { return toNumpy(s.cell.hSize); }
void setCellMatrix(Scene& s, const bp::object& o) {
  Cell c = s.cell;
  c.hSize = toMatrix3(o, "cell matrix");
  c.validate();  // singular or inverted: refused before anything changes
  s.cell = c;
  s.detectionInvalid = true;
}
np::ndarray cellRefMatrix(const Scene& s) { return toNumpy(s.cell.refHSize); }
void setCellRefMatrix(Scene& s, const bp::object& o) {
  Cell c = s.cell;
  c.refHSize = toMatrix3(o, "cell reference matrix");
  c.validate();
  s.cell = c;
}
np::ndarray velocityGradient(const Scene& s) { return toNumpy(s.cell.velGrad); }
void setVelocityGradient(Scene& s, const bp::object& o) {
  const Mat3 L = toMatrix3(o, "velocity gradient");
  require(L.allFinite(), "the velocity gradient must be finite");
  s.cell.velGrad = L;
}

// Orthorhombic conveniences: edge lengths and axial strain rates of a diagonal cell. Reading
// them from a sheared cell would drop its shear, so that is refused.
Vec3 diagonalOf(const Mat3& m, const char* what) {
  if (!Cell::isDiagonal(m))
    throw InputError(std::string("the cell is sheared: ") + what + " describes only an orthorhombic one (read "
                     "scene.cell, scene.cell_ref or scene.velocity_gradient)");
  return m.diagonal();
}
Vec3 positiveSizes(const bp::object& o, const char* what) {
  const Vec3 h = toVec3(o, what);
  require(h.allFinite() && (h.array() > 0).all(), std::string(what) + " must be > 0");
  return h;
}
np::ndarray cellSize(const Scene& s) { return toNumpy(diagonalOf(s.cell.hSize, "cell_size")); }
void setCellSize(Scene& s, const bp::object& o) {
  s.cell.hSize = positiveSizes(o, "cell sizes").asDiagonal();
  s.detectionInvalid = true;
}
np::ndarray cellRefSize(const Scene& s) { return toNumpy(diagonalOf(s.cell.refHSize, "cell_ref_size")); }
void setCellRefSize(Scene& s, const bp::object& o) { s.cell.refHSize = positiveSizes(o, "cell reference sizes").asDiagonal(); }
np::ndarray strainRate(const Scene& s) { return toNumpy(diagonalOf(s.cell.velGrad, "strain_rate")); }
void setStrainRate(Scene& s, const bp::object& o) {
  const Vec3 r = toVec3(o, "strain rate");
  require(r.allFinite(), "the strain rate must be finite");
  s.cell.velGrad = r.asDiagonal();
}
np::ndarray strain(const Scene& s) { return toNumpy(s.cell.strain()); }

Real getG(const Scene& s) { return s.material.shearModulus; }
void setG(Scene& s, Real v) { s.material.shearModulus = v; s.material.validate(); }
Real getNu(const Scene& s) { return s.material.poisson; }
void setNu(Scene& s, Real v) { s.material.poisson = v; s.material.validate(); }
Real getRho(const Scene& s) { return s.material.density; }
void setRho(Scene& s, Real v) { s.setDensity(v); }
Real getMu(const Scene& s) { return s.material.friction; }
void setMu(Scene& s, Real v) { s.material.friction = v; s.material.validate(); }
// Rolling resistance (Material): checked on a copy, so a refused value leaves the scene as it was.
template <Real Material::*field>
Real getMaterial(const Scene& s) { return s.material.*field; }
template <Real Material::*field>
void setMaterial(Scene& s, Real v) {
  Material m = s.material;
  m.*field = v;
  m.validate();
  s.material = m;
}

bp::dict contactArrays(const Scene& s) {
  const Contacts& C = s.contacts;
  bp::dict d;
  d["member1"] = toNumpy(C.m1); d["member2"] = toNumpy(C.m2);
  d["body1"] = toNumpy(C.b1); d["body2"] = toNumpy(C.b2);
  d["shift"] = toNumpy(C.shift); d["rbar"] = toNumpy(C.rbar);
  // Branch vectors of the last force evaluation; zeros before any (an imported history).
  std::vector<Vec3> branch(C.size(), Vec3::Zero());
  if (C.evaluated(s.bodies.size()))
    for (int c = 0; c < C.size(); ++c) branch[c] = C.branch(c);
  d["normal"] = toNumpy(C.normal); d["branch"] = toNumpy(branch);
  d["overlap"] = toNumpy(C.overlap); d["normal_force"] = toNumpy(C.normalForce);
  std::vector<Real> kn(C.size());
  std::vector<Vec3> force(C.size());
  for (int c = 0; c < C.size(); ++c) {
    kn[c] = HertzMindlin::normalStiffness(C.normalForce[c], C.overlap[c]);
    force[c] = C.force(c);
  }
  d["kn"] = toNumpy(kn); d["shear_force"] = toNumpy(C.shearForce); d["force"] = toNumpy(force);
  d["rolling_moment"] = toNumpy(C.rollingMoment);
  return d;
}

// History of existing contacts (from a specimen file or from YADE's interactions). The next
// detection keeps it for every pair it lists again; nothing else of the contacts is trusted.
void setContactHistory(Scene& s, const bp::object& m1o, const bp::object& m2o, const bp::object& shifto,
                       const bp::object& normalo, const bp::object& normalForceo, const bp::object& shearo,
                       const bp::object& rollingo) {
  std::vector<int> m1 = toIntList(m1o, "member1"), m2 = toIntList(m2o, "member2");
  std::vector<Vec3i> sh = toVec3iList(shifto, "shift");
  std::vector<Vec3> n = toVec3List(normalo, "normal"), fs = toVec3List(shearo, "shear_force");
  std::vector<Real> N = toRealList(normalForceo, "normal_force");
  const size_t k = m1.size();
  // None: no rolling history (a scene without rolling resistance, or a file from before it).
  std::vector<Vec3> mr = rollingo.is_none() ? std::vector<Vec3>(k, Vec3::Zero()) : toVec3List(rollingo, "rolling_moment");
  require(m2.size() == k && sh.size() == k && n.size() == k && fs.size() == k && N.size() == k && mr.size() == k,
          "contact history arrays must have the same length");
  const int nm = s.members.size();
  std::vector<size_t> order(k);
  std::iota(order.begin(), order.end(), 0);
  for (size_t i = 0; i < k; ++i) {
    require(m1[i] >= 0 && m2[i] >= 0 && m1[i] < nm && m2[i] < nm, "contact member index out of range");
    if (m1[i] > m2[i]) { std::swap(m1[i], m2[i]); sh[i] = -sh[i]; n[i] = -n[i]; fs[i] = -fs[i]; mr[i] = -mr[i]; }
  }
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    return std::tie(m1[a], m2[a], sh[a][0], sh[a][1], sh[a][2]) < std::tie(m1[b], m2[b], sh[b][0], sh[b][1], sh[b][2]);
  });
  Contacts C;
  C.resize(static_cast<int>(k));
  for (size_t q = 0; q < k; ++q) {
    const size_t i = order[q];
    C.m1[q] = m1[i]; C.m2[q] = m2[i]; C.b1[q] = s.members.body[m1[i]]; C.b2[q] = s.members.body[m2[i]];
    C.shift[q] = sh[i]; C.normal[q] = n[i]; C.normalForce[q] = N[i]; C.shearForce[q] = fs[i];
    C.rollingMoment[q] = mr[i];
    const Real r1 = s.members.radius[m1[i]], r2 = s.members.radius[m2[i]];
    C.rbar[q] = 2 * r1 * r2 / (r1 + r2);
  }
  s.contacts = std::move(C);
  s.detectionInvalid = true;
}

ScenePtr copyScene(const Scene& s) { return std::make_shared<Scene>(s); }
void assignScene(Scene& s, const Scene& other) { s = other; }
int numBodies(const Scene& s) { return s.bodies.size(); }
int numMembers(const Scene& s) { return s.members.size(); }
int numPairs(const Scene& s) { return s.contacts.size(); }
bool hasClumps(const Scene& s) { return s.hasClumps(); }
void invalidate(Scene& s) { s.detectionInvalid = true; }
Real cn(const Scene& s) { return s.material.Cn(); }
Real cs(const Scene& s) { return s.material.Cs(); }

}  // namespace

void exportScene() {
  bp::class_<Scene, ScenePtr>("Scene", "Periodic cell (a full 3x3 matrix, as YADE's), bodies (clumps of >= 1 spheres), contacts.")
      .def("add_spheres", &addSpheres, (bp::arg("positions"), bp::arg("radii")))
      .def("add_sphere", +[](Scene& s, const bp::object& p, Real r) { return s.addSphere(toVec3(p, "position"), r); })
      .def("add_clump", &addClump,
           (bp::arg("position"), bp::arg("orientation"), bp::arg("offsets"), bp::arg("radii"), bp::arg("mass"),
            bp::arg("inertia"), bp::arg("volume") = 0.0),
           "A rigid clump; its solid volume is `volume` when > 0 (a saved scene's), else the members' union (CGAL).")
      .def("copy", &copyScene, "Deep copy (state snapshot).")
      .def("assign", &assignScene, "Overwrite this scene with another's state.")
      .def("order_in_space", &orderInSpace,
           "Renumber the bodies along a Morton curve (core/SpaceOrder.hpp), contacts and their history kept; "
           "returns the order (new body k was body order[k]).")
      .def("reorder_bodies", &reorder, (bp::arg("order")),
           "Renumber the bodies: new body k is old body order[k]; contacts and their history kept.")
      .def("rescale", &Scene::rescale, "Geometric similarity of all lengths; Hertz stresses are unchanged.")
      .def("invalidate_contacts", &invalidate, "Force a contact list rebuild before the next force evaluation.")
      .def("set_contact_history", &setContactHistory,
           (bp::arg("member1"), bp::arg("member2"), bp::arg("shift"), bp::arg("normal"), bp::arg("normal_force"),
            bp::arg("shear_force"), bp::arg("rolling_moment") = bp::object()))
      .def("contact_arrays", &contactArrays, "All listed pairs; a pair is a contact where normal_force > 0.")
      .add_property("positions", &getBodyVec<&Bodies::pos>, &setBodyVec<&Bodies::pos>)
      .add_property("velocities", &getBodyVec<&Bodies::vel>, &setBodyVec<&Bodies::vel>)
      .add_property("angular_velocities", &getBodyVec<&Bodies::angVel>, &setBodyVec<&Bodies::angVel>)
      .add_property("forces", &getBodyVec<&Bodies::force>)
      .add_property("torques", &getBodyVec<&Bodies::torque>)
      .add_property("orientations", &orientations, &setOrientations)
      .add_property("masses", &masses)
      .add_property("volumes", +[](const Scene& s) { return toNumpy(s.bodies.volume); },
                    "Solid volume of each body (a clump's union, overlaps once).")
      .add_property("inertia", &inertia)
      .add_property("member_begin", &memberBegin)
      .add_property("radii", &radii, &setRadii)
      .add_property("member_body", &memberBody)
      .add_property("member_offsets", &memberOffsets)
      .add_property("member_positions", &memberPositions)
      .add_property("cell", &cellMatrix, &setCellMatrix,
                    "Cell matrix hSize (3x3, columns = cell vectors), as YADE's O.cell.hSize; a singular or "
                    "inverted matrix is refused.")
      .add_property("cell_ref", &cellRefMatrix, &setCellRefMatrix, "Cell matrix at zero strain (YADE's refHSize).")
      .add_property("velocity_gradient", &velocityGradient, &setVelocityGradient,
                    "Velocity gradient L of the affine field v = L x (YADE's O.cell.velGrad).")
      .add_property("cell_size", &cellSize, &setCellSize, "Edge lengths of an orthorhombic cell (sets a diagonal cell).")
      .add_property("cell_ref_size", &cellRefSize, &setCellRefSize)
      .add_property("strain_rate", &strainRate, &setStrainRate, "Diagonal of the velocity gradient (sets a diagonal one).")
      .add_property("strain", &strain,
                    "Logarithmic cell strain since cell_ref, Voigt (xx, yy, zz, yz, xz, xy, engineering shears), "
                    "compression positive.")
      .add_property("deformation_gradient", +[](const Scene& s) { return toNumpy(s.cell.deformation()); })
      .add_property("orthorhombic", +[](const Scene& s) { return s.cell.orthorhombic(); },
                    "True when hSize and the velocity gradient are diagonal (the fast path).")
      .add_property("cell_widths", +[](const Scene& s) { return toNumpy(s.cell.widths()); },
                    "Distances between opposite faces of the cell.")
      .add_property("volume", +[](const Scene& s) { return s.cell.volume(); })
      .add_property("shear_modulus", &getG, &setG)
      .add_property("poisson", &getNu, &setNu)
      .add_property("density", &getRho, &setRho)
      .add_property("friction", &getMu, &setMu, "Coulomb coefficient of all contacts, switchable at run time.")
      .add_property("rolling_stiffness", &getMaterial<&Material::rollingStiffness>,
                    &setMaterial<&Material::rollingStiffness>,
                    "Rolling resistance (not in the paper; docs/rolling.md): beta of k_r = beta k_s rbar^2; 0 (the "
                    "default) turns it off.")
      .add_property("rolling_friction", &getMaterial<&Material::rollingFriction>,
                    &setMaterial<&Material::rollingFriction>,
                    "Rolling resistance: eta_r of the cap eta_r rbar N on the rolling moment.")
      .add_property("Cn", &cn, "C_n of Eq. (5)")
      .add_property("Cs", &cs, "C_s of Eq. (6)")
      .def_readwrite("dt", &Scene::dt)
      .def_readwrite("reference_dt", &Scene::referenceDt,
                     "The step of the reference time step rule (0: unknown), the unit of the servos' per-step settings.")
      .add_property("step_scale", &Scene::stepScale, "dt / reference_dt (1 while reference_dt is 0).")
      .def_readwrite("time", &Scene::time)
      .def_readwrite("step", &Scene::step)
      .def_readwrite("block_rotations", &Scene::blockRotations)
      .add_property("num_bodies", &numBodies)
      .add_property("num_members", &numMembers)
      .add_property("num_pairs", &numPairs)
      .add_property("has_clumps", &hasClumps);
}

}  // namespace trueaniso::py
