// Static stiffness of the contact network as seen from Python: a function taking the scene and
// the solver's parameters, returning a dict of numpy arrays and numbers. No physics here.
#include "python/Numpy.hpp"
#include "statics/RotationFactor.hpp"
#include "statics/StaticStiffness.hpp"

namespace trueaniso::py {

namespace {

template <class M>
np::ndarray matrix(const M& m) {
  np::ndarray a = np::zeros(bp::make_tuple(m.rows(), m.cols()), np::dtype::get_builtin<double>());
  auto* d = reinterpret_cast<double*>(a.get_data());
  for (int i = 0; i < m.rows(); ++i)
    for (int j = 0; j < m.cols(); ++j) d[i * m.cols() + j] = m(i, j);
  return a;
}

Mat6 toMat6(const bp::object& o, const std::string& what) {
  const std::vector<Real> v = toRealList(bp::import("numpy").attr("ravel")(o), what);
  require(v.size() == 36, what + " must be a 6x6 matrix");
  Mat6 m;
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) m(i, j) = v[6 * i + j];
  return m;
}

bp::dict staticStiffness(const Scene& scene, bool rotations, Real maxUnbalanced, Real pivotTolerance,
                         Real zeroModeTolerance, Real softModeTolerance, Real tolerance, int maxIterations) {
  StaticStiffness st;
  st.rotations = rotations;
  st.maxUnbalanced = maxUnbalanced;
  st.pivotTolerance = pivotTolerance;
  st.zeroModeTolerance = zeroModeTolerance;
  st.softModeTolerance = softModeTolerance;
  st.tolerance = tolerance;
  st.maxIterations = maxIterations;
  StaticStiffnessResult r;
  {
    // The solve can take seconds: let other Python threads (progress, YADE's UI) run meanwhile.
    PyThreadState* state = PyEval_SaveThread();
    try {
      r = st.compute(scene);
    } catch (...) {
      PyEval_RestoreThread(state);
      throw;
    }
    PyEval_RestoreThread(state);
  }
  bp::dict d;
  d["C"] = matrix(r.C);
  d["S"] = matrix(r.compliance);
  d["E"] = toNumpy(r.constants.E);
  d["nu"] = toNumpy(r.constants.nu);
  d["G"] = toNumpy(r.constants.G);
  d["affine"] = matrix(r.affine);
  d["affine_normal"] = matrix(r.affineNormal);
  d["affine_shear"] = matrix(r.affineShear);
  d["affine_geometric"] = matrix(r.affineGeometric);
  d["stress"] = toNumpy(r.stress);
  d["volume"] = r.volume;
  d["unbalanced_force"] = r.unbalancedForce;
  d["unbalanced_torque"] = r.unbalancedTorque;
  d["residual"] = r.residual;
  d["pinned_reaction"] = r.pinnedReaction;
  d["iterations"] = r.iterations;
  d["gmres_iterations"] = r.gmresIterations;
  d["factorizations"] = r.factorizations;
  d["rattlers"] = toNumpy(r.rattlers);
  bp::list pinned;
  for (const PinnedDof& p : r.pinned) {
    bp::dict q;
    q["body"] = p.body;
    q["translation"] = toNumpy(p.translation);
    q["rotation"] = toNumpy(p.rotation);
    q["reason"] = p.reason;
    q["ratio"] = p.ratio;
    pinned.append(q);
  }
  d["pinned"] = pinned;
  d["rotations"] = r.rotations;
  d["bodies"] = r.bodies;
  d["dofs"] = r.dofs;
  d["contacts"] = r.contacts;
  d["factor_nonzeros"] = r.factorNonzeros;
  d["factor_flops"] = r.factorFlops;
  d["supernodal"] = r.supernodal;
  bp::dict t;
  t["held_state"] = r.timeHeld;
  t["assembly"] = r.timeAssembly;
  t["analysis"] = r.timeAnalysis;
  t["factorization"] = r.timeFactorization;
  t["solve"] = r.timeSolve;
  t["total"] = r.timeTotal;
  d["time"] = t;
  return d;
}

bp::dict rotationFactorDict(const bp::object& normal, const bp::object& shear, const bp::object& free,
                            const bp::object& blocked) {
  const RotationFactor z = rotationFactor(toMat6(normal, "affine_normal"), toMat6(shear, "affine_shear"),
                                          toVec3(free, "E (rotations free)"), toVec3(blocked, "E (rotations blocked)"));
  bp::dict d;
  d["zeta"] = toNumpy(z.zeta);
  d["zeta_h"] = z.zetaH;
  d["zeta_v"] = z.zetaV;
  d["zeta_rotation"] = toNumpy(z.zetaRotation);
  d["zeta_rotation_h"] = z.zetaRotationH;
  d["zeta_rotation_v"] = z.zetaRotationV;
  return d;
}

np::ndarray kinematic(const bp::object& normal, const bp::object& shear, Real zeta) {
  return toNumpy(kinematicModuli(toMat6(normal, "affine_normal"), toMat6(shear, "affine_shear"), zeta));
}

}  // namespace

void exportStatics() {
  bp::def("static_stiffness", &staticStiffness,
          (bp::arg("scene"), bp::arg("rotations") = true, bp::arg("max_unbalanced") = 1e-2,
           bp::arg("pivot_tolerance") = 1e-9, bp::arg("zero_mode_tolerance") = 1e-6,
           bp::arg("soft_mode_tolerance") = 1e-2, bp::arg("tolerance") = 1e-12,
           bp::arg("max_iterations") = 200),
          "Exact static 6x6 stiffness of the contact network at the scene's state (see docs/statics.md).");
  bp::def("rotation_factor", &rotationFactorDict,
          (bp::arg("affine_normal"), bp::arg("affine_shear"), bp::arg("E_free"), bp::arg("E_blocked")),
          "zeta of Eq. (37) from relaxed static moduli (see docs/statics.md).");
  bp::def("kinematic_moduli", &kinematic, (bp::arg("affine_normal"), bp::arg("affine_shear"), bp::arg("zeta")),
          "E_i of Eq. (40) from C = A_n + zeta A_s (Eq. 37).");
}

}  // namespace trueaniso::py
