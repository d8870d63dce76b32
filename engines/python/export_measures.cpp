// Measures as free functions returning numpy arrays or plain numbers.
#include "measure/Coordination.hpp"
#include "measure/Stress.hpp"
#include "python/Numpy.hpp"

namespace trueaniso::py {

namespace {

np::ndarray stress(const Scene& s) { return toNumpy(loveWeberStress(s)); }
np::ndarray axialStiffness(const Scene& s) { return toNumpy(affineAxialStiffness(s)); }
bp::dict coordinationDict(const Scene& s) {
  const Coordination z = coordination(s);
  bp::dict d;
  d["Nc"] = z.contacts; d["Np"] = z.particles; d["Np0"] = z.noContact; d["Np1"] = z.oneContact;
  d["Zm"] = z.mechanical(); d["Z"] = z.plain();
  return d;
}
np::ndarray perBody(const Scene& s) { return toNumpy(contactsPerBody(s)); }

}  // namespace

void exportMeasures() {
  bp::def("stress", &stress, "Love-Weber stress tensor (Pa, compression positive) = -YADE getStress().");
  bp::def("unbalanced_force", &unbalancedForce, "YADE's unbalancedForce(useMaxForce=False).");
  bp::def("unbalanced_torque", &unbalancedTorque,
          "Mean |resultant torque| / (mean |contact force| x mean lever arm); valid after a force evaluation.");
  bp::def("affine_axial_stiffness", &axialStiffness);
  bp::def("coordination", &coordinationDict, "Nc, Np, Np0, Np1, Zm (Eq. 14) and Z = 2Nc/Np.");
  bp::def("contacts_per_body", &perBody);
  bp::def("void_ratio", &voidRatio);
}

}  // namespace trueaniso::py
