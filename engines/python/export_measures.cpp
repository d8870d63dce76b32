// Measures as free functions returning numpy arrays or plain numbers.
#include "measure/Coordination.hpp"
#include "measure/Energy.hpp"
#include "measure/Stress.hpp"
#include "python/Numpy.hpp"

namespace trueaniso::py {

namespace {

np::ndarray stress(const Scene& s) { return toNumpy(loveWeberStress(s)); }
np::ndarray stiffness6(const Scene& s) { return toNumpy(affineStiffness(s)); }
np::ndarray principal(const bp::object& sigma) { return toNumpy(principalStresses(toMatrix3(sigma, "stress tensor"))); }
bp::dict countsDict(const Coordination& z) {
  bp::dict d;
  d["Nc"] = z.contacts; d["Np"] = z.particles; d["Np0"] = z.noContact; d["Np1"] = z.oneContact;
  d["Zm"] = z.mechanical(); d["Z"] = z.plain();
  return d;
}
bp::dict coordinationDict(const Scene& s) { return countsDict(coordination(s)); }
bp::dict coordinationGapDict(const Scene& s, Real tol) { return countsDict(coordinationWithinGap(s, tol)); }
np::ndarray perBody(const Scene& s) { return toNumpy(contactsPerBody(s)); }
bp::dict energyDict(const Scene& s) {
  const MechanicalEnergy e = mechanicalEnergy(s);
  bp::dict d;
  d["translational"] = e.translational; d["rotational"] = e.rotational; d["normal"] = e.normal;
  d["tangential"] = e.tangential; d["rolling"] = e.rolling; d["total"] = e.total();
  return d;
}

}  // namespace

void exportMeasures() {
  bp::def("stress", &stress, "Love-Weber stress tensor (Pa, compression positive) = -YADE getStress().");
  bp::def("unbalanced_force", &unbalancedForce, "YADE's unbalancedForce(useMaxForce=False).");
  bp::def("affine_stiffness", &stiffness6,
          "Diagonal of the affine (Eq. 32) stiffness per Voigt component xx, yy, zz, yz, xz, xy (Pa).");
  bp::def("principal_stresses", &principal, (bp::arg("sigma")),
          "Principal values of the symmetric part of a 3x3 stress, largest first.");
  bp::def("unbalanced_torque", &unbalancedTorque,
          "Mean |resultant torque| / (mean |contact force| x mean lever arm); valid after a force evaluation.");
  bp::def("coordination", &coordinationDict, "Nc, Np, Np0, Np1, Zm (Eq. 14) and Z = 2Nc/Np.");
  bp::def("coordination_gap", &coordinationGapDict, (bp::arg("scene"), bp::arg("tolerance") = kGapTolerance),
          "The counts of coordination() with near-contacts: a pair counts when its gap is below tolerance x (r1 + r2) "
          "(measure/Coordination.hpp); needs forces evaluated after the last detection (a loaded or stepped scene).");
  bp::scope().attr("GAP_TOLERANCE") = kGapTolerance;
  bp::def("contacts_per_body", &perBody);
  bp::def("mechanical_energy", &energyDict,
          "Kinetic (translational, rotational) and elastic (normal, tangential, rolling) energy and their total (J), "
          "measure/Energy.hpp; valid after a force evaluation.");
  bp::def("void_ratio", &voidRatio);
}

}  // namespace trueaniso::py
