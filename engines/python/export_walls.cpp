// Rigid frictionless walls and their servo (boundary/RigidWalls.hpp) as seen from Python.
#include <memory>

#include "boundary/RigidWalls.hpp"
#include "python/Numpy.hpp"

namespace trueaniso::py {

namespace {

template <Vec3 RigidWalls::*F>
np::ndarray getVec(const RigidWalls& w) { return toNumpy(w.*F); }
template <Vec3 RigidWalls::*F>
void setVec(RigidWalls& w, const bp::object& o) { w.*F = toVec3(o, "wall vector"); }
template <Vec6 RigidWalls::*F>
np::ndarray getVec6(const RigidWalls& w) { return toNumpy(w.*F); }

np::ndarray wallContacts(const RigidWalls& w) {
  return toNumpy(std::vector<int>(w.contacts.data(), w.contacts.data() + 6));
}
void setBox(RigidWalls& w, const bp::object& lower, const bp::object& upper) {
  w.setBox(toVec3(lower, "lower walls"), toVec3(upper, "upper walls"));
}
np::ndarray wallStress(const RigidWalls& w) { return toNumpy(w.stress()); }
np::ndarray wallWidth(const RigidWalls& w) { return toNumpy(w.width()); }
bp::dict measurementDict(const RigidWalls& w, const Scene& s) {
  const CellMeasurement m = w.measurement(s);
  bp::dict d;
  d["stress"] = toNumpy(m.stress);
  d["deformation"] = toNumpy(m.deformation);
  d["stiffness"] = toNumpy(m.stiffness);
  d["unbalanced"] = m.unbalanced;
  return d;
}

}  // namespace

void exportWalls() {
  bp::class_<RigidWalls, bp::bases<Engine>, std::shared_ptr<RigidWalls>>("RigidWalls")
      .def("set_box", &setBox, (bp::arg("lower"), bp::arg("upper")),
           "Walls at the planes x_k = lower_k and x_k = upper_k; their gaps become the reference; rate 0.")
      .add_property("lower", &getVec<&RigidWalls::lo>, &setVec<&RigidWalls::lo>, "Lower wall positions (m).")
      .add_property("upper", &getVec<&RigidWalls::hi>, &setVec<&RigidWalls::hi>, "Upper wall positions (m).")
      .add_property("ref_width", &getVec<&RigidWalls::refWidth>, &setVec<&RigidWalls::refWidth>,
                    "Wall gaps at zero strain (m).")
      .add_property("rate", &getVec<&RigidWalls::rate>, &setVec<&RigidWalls::rate>,
                    "Engineering strain rate of each wall pair (1/s, extension positive).")
      .def_readwrite("margin", &RigidWalls::margin,
                     "Room (m) kept between the box and the cell faces on top of the largest diameter.")
      .add_property("width", &wallWidth, "Wall gaps (m).")
      .add_property("volume", &RigidWalls::boxVolume, "Volume of the walled box (m^3).")
      .def("area", &RigidWalls::area, (bp::arg("axis")), "Area of the walls normal to the axis (m^2).")
      .add_property("stress", &wallStress, "Mean wall force over area per axis (Pa, compression positive).")
      .add_property("force", &getVec6<&RigidWalls::force>,
                    "Normal force on each wall (x lo, x hi, y lo, y hi, z lo, z hi), N, > 0 pushing it out.")
      .add_property("stiffness", &getVec6<&RigidWalls::stiffness>, "Sum of each wall's contact k_n (N/m).")
      .add_property("contacts", &wallContacts, "Spheres touching each wall.")
      .def_readonly("max_overlap", &RigidWalls::maxOverlap, "Largest wall overlap (m).")
      .def("add_forces", &RigidWalls::addForces, (bp::arg("scene")),
           "Add the wall forces of the current positions to the bodies (the walls do not move).")
      .def("validate", &RigidWalls::validate, (bp::arg("scene")))
      .def("measurement", &measurementDict, (bp::arg("scene")),
           "What the wall servo reads: stress, deformation, stiffness (Voigt) and the unbalanced force.")
      .def("normal_force", +[](const Scene& s, Real r, Real overlap) { return RigidWalls::normalForce(s.material, r, overlap); },
           (bp::arg("scene"), bp::arg("radius"), bp::arg("overlap")),
           "Hertz force of a sphere of the scene's material against a wall (N).")
      .staticmethod("normal_force");

  bp::class_<WallServo, bp::bases<Engine>, std::shared_ptr<WallServo>>(
      "WallServo", bp::init<std::shared_ptr<RigidWalls>, std::shared_ptr<TrueTriaxialServo>>(
                       (bp::arg("walls"), bp::arg("path"))))
      .def("start", &WallServo::start, (bp::arg("scene")),
           "Check the path (shear control off) and set its loading friction on the scene; required before running.")
      .def_readonly("walls", &WallServo::walls)
      .def_readonly("path", &WallServo::path);
}

}  // namespace trueaniso::py
