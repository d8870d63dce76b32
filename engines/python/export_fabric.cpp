// Fabric measures (Eqs. 14-16, 33-36), the micromechanical prediction (Eqs. 35-42, A1-A9) and the
// fabric recorder, as numpy arrays and plain numbers.
#include <memory>
#include <string>

#include "measure/Fabric.hpp"
#include "measure/FabricRecorder.hpp"
#include "python/Numpy.hpp"
#include "theory/HertzRange.hpp"
#include "theory/Micromechanics.hpp"

namespace trueaniso::py {

namespace {

np::ndarray shaped(const std::vector<Real>& flat, const bp::tuple& shape) {
  return toNumpy(flat).reshape(shape);
}

np::ndarray tensor4(const Mat9& T) {
  std::vector<Real> v(81);
  for (int a = 0; a < 9; ++a)
    for (int b = 0; b < 9; ++b) v[9 * a + b] = T(a, b);
  return shaped(v, bp::make_tuple(3, 3, 3, 3));
}

np::ndarray matrix6(const Mat6& C) {
  std::vector<Real> v(36);
  for (int a = 0; a < 6; ++a)
    for (int b = 0; b < 6; ++b) v[6 * a + b] = C(a, b);
  return shaped(v, bp::make_tuple(6, 6));
}

np::ndarray longs(const std::vector<long>& v) {
  np::ndarray a = np::zeros(bp::make_tuple(v.size()), np::dtype::get_builtin<long>());
  std::copy(v.begin(), v.end(), reinterpret_cast<long*>(a.get_data()));
  return a;
}

std::vector<Real> flatReals(const bp::object& o, size_t n, const std::string& what) {
  std::vector<Real> v = toRealList(bp::import("numpy").attr("ravel")(o), what);
  if (v.size() != n) throw InputError(what + " must have " + std::to_string(n) + " components");
  return v;
}

Mat3 toMat3(const bp::object& o, const std::string& what) {
  const std::vector<Real> v = flatReals(o, 9, what + " (3x3)");
  Mat3 m;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) m(i, j) = v[3 * i + j];
  return m;
}

Mat9 toMat9(const bp::object& o, const std::string& what) {
  const std::vector<Real> v = flatReals(o, 81, what + " (3x3x3x3)");
  Mat9 m;
  for (int a = 0; a < 9; ++a)
    for (int b = 0; b < 9; ++b) m(a, b) = v[9 * a + b];
  return m;
}

Mat6 toMat6(const bp::object& o, const std::string& what) {
  const std::vector<Real> v = flatReals(o, 36, what + " (6x6)");
  Mat6 m;
  for (int a = 0; a < 6; ++a)
    for (int b = 0; b < 6; ++b) m(a, b) = v[6 * a + b];
  return m;
}

bp::dict fabricDict(const Fabric& f) {
  bp::dict d;
  d["Zm"] = f.Zm;
  d["Nc"] = f.counts.contacts; d["Np"] = f.counts.particles;
  d["Np0"] = f.counts.noContact; d["Np1"] = f.counts.oneContact;
  d["R"] = toNumpy(f.R); d["H"] = toNumpy(f.H); d["B"] = toNumpy(f.B); d["M"] = tensor4(f.M);
  d["NcV_eq36"] = f.contactDensityEq36(); d["NcV_count"] = f.contactDensityCount();
  d["e"] = f.voidRatio; d["mean_N"] = f.meanNormalForce; d["volume"] = f.volume;
  d["mean_r3"] = f.meanRadiusCubed;
  return d;
}

bp::dict modulusDict(const OrthotropicModuli& m) {
  bp::dict d;
  d["E"] = toNumpy(m.E); d["nu"] = toNumpy(m.nu); d["G"] = toNumpy(m.G); d["Delta"] = m.Delta;
  return d;
}

bp::dict predictionDict(const MicromechanicalPrediction& p) {
  bp::dict d = modulusDict(p.moduli);
  d["C"] = tensor4(p.C); d["voigt"] = matrix6(p.voigt);
  d["zeta"] = p.zeta; d["contact_density"] = p.contactDensity;
  return d;
}

ContactDensity densityFrom(const std::string& s) {
  if (s == "eq36") return ContactDensity::Eq36;
  if (s == "count") return ContactDensity::Count;
  throw InputError("contact density must be 'eq36' (Eq. 36) or 'count' (Nc/V counted), not '" + s + "'");
}

bp::dict fabricOf(const Scene& s) { return fabricDict(fabric(s)); }

bp::dict predictScene(const Scene& s, Real zeta, const std::string& density) {
  return predictionDict(predict(fabric(s), s.material, zeta, densityFrom(density)));
}

bp::dict micromechanics(const bp::object& B, const bp::object& M, Real contactDensity, Real Cn, Real Cs, Real zeta) {
  return predictionDict(predict(toMat3(B, "B"), toMat9(M, "M"), contactDensity, Cn, Cs, zeta));
}

bp::dict orthotropic(const bp::object& C) { return modulusDict(orthotropicModuli(toMat6(C, "stiffness"))); }

bp::dict history(const FabricRecorder& r) {
  const FabricHistory& h = r.history;
  const int n = h.size();
  bp::dict d;
  d["step"] = longs(h.step); d["time"] = toNumpy(h.time);
  d["Nc"] = longs(h.contacts); d["Np"] = longs(h.particles);
  d["Np0"] = longs(h.noContact); d["Np1"] = longs(h.oneContact);
  d["Zm"] = toNumpy(h.Zm);
  d["NcV_eq36"] = toNumpy(h.contactDensityEq36); d["NcV_count"] = toNumpy(h.contactDensityCount);
  d["e"] = toNumpy(h.voidRatio); d["mean_N"] = toNumpy(h.meanNormalForce);
  d["volume"] = toNumpy(h.volume); d["mean_r3"] = toNumpy(h.meanRadiusCubed);
  d["R"] = shaped(h.R, bp::make_tuple(n, 3, 3));
  d["H"] = shaped(h.H, bp::make_tuple(n, 3, 3));
  d["B"] = shaped(h.B, bp::make_tuple(n, 3, 3));
  d["M"] = shaped(h.M, bp::make_tuple(n, 3, 3, 3, 3));
  return d;
}

bp::dict lastRecord(const FabricRecorder& r) {
  require(r.history.size() > 0, "the recorder has not recorded anything yet");
  return fabricDict(r.last);
}

int historySize(const FabricRecorder& r) { return r.history.size(); }
void clearHistory(FabricRecorder& r) { r.history.clear(); }
void reserveHistory(FabricRecorder& r, int rows) {
  require(rows >= 0, "rows must be >= 0");
  r.history.reserve(rows);
}

}  // namespace

void exportFabric() {
  bp::scope().attr("ZETA_RANGE") = bp::make_tuple(ZetaRange::lo, ZetaRange::hi);
  bp::scope().attr("MAX_OVERLAP_RATIO") = kMaxOverlapRatio;
  bp::def(
      "hertz_overlap_ratio",
      +[](Real shearModulus, Real poisson, Real pressure, Real solidFraction, Real coordination) {
        Material m;
        m.shearModulus = shearModulus;
        m.poisson = poisson;
        return hertzOverlapRatio(m, pressure, solidFraction, coordination);
      },
      (bp::arg("shear_modulus"), bp::arg("poisson"), bp::arg("pressure"), bp::arg("solid_fraction"),
       bp::arg("coordination")),
      "Mean overlap over the radius, delta/R, of equal Hertz spheres at mean stress `pressure` (theory/HertzRange.hpp).");
  bp::def("fabric", &fabricOf,
          "Zm (Eq. 14), R (15), H (16), B (33), M (34, shape 3x3x3x3), NcV_eq36 (36), NcV_count, e, mean_N, "
          "Nc, Np, Np0, Np1 of the last force evaluation.");
  bp::def("micromechanical_prediction", &predictScene,
          (bp::arg("scene"), bp::arg("zeta") = 1.0, bp::arg("density") = "eq36"),
          "Eq. (37) from the scene's fabric, its Voigt matrix (Appendix A) and E, nu, G (Eqs. 39-42); "
          "density 'eq36' or 'count' selects Nc/V.");
  bp::def("micromechanics", &micromechanics,
          (bp::arg("B"), bp::arg("M"), bp::arg("contact_density"), bp::arg("Cn"), bp::arg("Cs"), bp::arg("zeta") = 1.0),
          "Eq. (37) from given B, M, Nc/V, C_n, C_s and zeta, with Appendix A and Eqs. (39)-(42).");
  bp::def("orthotropic_moduli", &orthotropic, (bp::arg("voigt")),
          "E (Eq. 40), nu[i, j] = nu_ij (Eq. 42 corrected), G = (G_yz, G_xz, G_xy) (Eq. 39) of a 6x6 "
          "Voigt stiffness (order xx, yy, zz, yz, xz, xy).");

  bp::class_<FabricRecorder, bp::bases<Engine>, std::shared_ptr<FabricRecorder>>(
      "FabricRecorder", "Records the fabric every `every` steps (default 100); place it after ContactForces.")
      .def("history", &history, "All records as numpy arrays (tensors shaped (n, 3, 3) and (n, 3, 3, 3, 3)).")
      .def("last", &lastRecord, "The latest record as a dict like fabric(scene).")
      .def("clear", &clearHistory)
      .def("reserve", &reserveHistory, "Reserve memory for this many records.")
      .add_property("size", &historySize);
}

}  // namespace trueaniso::py
