// Boost.Python module: bindings only, no physics (that lives in engines/).
#include <boost/python.hpp>
#include <boost/python/numpy.hpp>

#include "core/Voigt.hpp"
#include "python/Numpy.hpp"

namespace trueaniso::py {

void exportScene();
void exportEngines();
void exportMeasures();
void exportStatics();
void exportFabric();
void exportControl();
void exportClump();

np::ndarray toNumpy(const std::vector<Vec3>& v) {
  np::ndarray a = np::zeros(bp::make_tuple(v.size(), 3), np::dtype::get_builtin<double>());
  auto* d = reinterpret_cast<double*>(a.get_data());
  for (size_t i = 0; i < v.size(); ++i)
    for (int k = 0; k < 3; ++k) d[3 * i + k] = v[i][k];
  return a;
}
np::ndarray toNumpy(const std::vector<Vec3i>& v) {
  np::ndarray a = np::zeros(bp::make_tuple(v.size(), 3), np::dtype::get_builtin<int>());
  auto* d = reinterpret_cast<int*>(a.get_data());
  for (size_t i = 0; i < v.size(); ++i)
    for (int k = 0; k < 3; ++k) d[3 * i + k] = v[i][k];
  return a;
}
np::ndarray toNumpy(const std::vector<Real>& v) {
  np::ndarray a = np::zeros(bp::make_tuple(v.size()), np::dtype::get_builtin<double>());
  std::copy(v.begin(), v.end(), reinterpret_cast<double*>(a.get_data()));
  return a;
}
np::ndarray toNumpy(const std::vector<int>& v) {
  np::ndarray a = np::zeros(bp::make_tuple(v.size()), np::dtype::get_builtin<int>());
  std::copy(v.begin(), v.end(), reinterpret_cast<int*>(a.get_data()));
  return a;
}
np::ndarray toNumpy(const Vec3& v) { return toNumpy(std::vector<Real>{v[0], v[1], v[2]}); }
np::ndarray toNumpy(const Mat3& m) {
  np::ndarray a = np::zeros(bp::make_tuple(3, 3), np::dtype::get_builtin<double>());
  auto* d = reinterpret_cast<double*>(a.get_data());
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) d[3 * i + j] = m(i, j);
  return a;
}

np::ndarray toNumpy(const Vec6& v) { return toNumpy(std::vector<Real>(v.data(), v.data() + 6)); }

namespace {

template <class T>
np::ndarray asArray(const bp::object& o) {
  // numpy.ascontiguousarray does dtype conversion and gives C order in one call.
  bp::object numpy = bp::import("numpy");
  bp::object arr = numpy.attr("ascontiguousarray")(o, np::dtype::get_builtin<T>());
  return bp::extract<np::ndarray>(arr);
}

template <class T, class V>
std::vector<V> rows3(const bp::object& o, const std::string& what) {
  np::ndarray a = asArray<T>(o);
  if (a.get_nd() == 1 && a.shape(0) == 0) return {};
  if (a.get_nd() != 2 || a.shape(1) != 3) throw InputError(what + " must be an array of shape (n, 3)");
  const T* d = reinterpret_cast<const T*>(a.get_data());
  std::vector<V> out(a.shape(0));
  for (size_t i = 0; i < out.size(); ++i) out[i] = V(d[3 * i], d[3 * i + 1], d[3 * i + 2]);
  return out;
}

template <class T>
std::vector<T> flat(const bp::object& o, const std::string& what) {
  np::ndarray a = asArray<T>(o);
  if (a.get_nd() != 1) throw InputError(what + " must be a one-dimensional array");
  const T* d = reinterpret_cast<const T*>(a.get_data());
  return std::vector<T>(d, d + a.shape(0));
}

void translateInputError(const InputError& e) { PyErr_SetString(PyExc_ValueError, e.what()); }

}  // namespace

std::vector<Vec3> toVec3List(const bp::object& o, const std::string& what) { return rows3<double, Vec3>(o, what); }
std::vector<Vec3i> toVec3iList(const bp::object& o, const std::string& what) { return rows3<int, Vec3i>(o, what); }
std::vector<Real> toRealList(const bp::object& o, const std::string& what) { return flat<double>(o, what); }
std::vector<int> toIntList(const bp::object& o, const std::string& what) { return flat<int>(o, what); }
Vec3 toVec3(const bp::object& o, const std::string& what) {
  const std::vector<Real> v = flat<double>(o, what);
  if (v.size() != 3) throw InputError(what + " must have three components");
  return Vec3(v[0], v[1], v[2]);
}
Vec6 toVec6(const bp::object& o, const std::string& what) {
  const std::vector<Real> v = flat<double>(o, what);
  if (v.size() != 6) throw InputError(what + " must have six components (xx, yy, zz, yz, xz, xy)");
  return Eigen::Map<const Vec6>(v.data());
}
Mat3 toMatrix3(const bp::object& o, const std::string& what) {
  const std::vector<Real> v = flat<double>(bp::import("numpy").attr("ravel")(o), what);
  if (v.size() != 9) throw InputError(what + " must be a 3x3 matrix");
  Mat3 m;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) m(i, j) = v[3 * i + j];
  return m;
}
Vec6 toStressVoigt(const bp::object& o, const std::string& what) {
  const std::vector<Real> v = flat<double>(bp::import("numpy").attr("ravel")(o), what);
  Vec6 s = Vec6::Zero();
  if (v.size() == 3) s.head<3>() = Vec3(v[0], v[1], v[2]);
  else if (v.size() == 6) s = Eigen::Map<const Vec6>(v.data());
  else if (v.size() == 9) s = voigt::fromTensor(toMatrix3(o, what));
  else throw InputError(what + " must be 3 normal stresses, 6 Voigt components (xx, yy, zz, yz, xz, xy) or a 3x3 tensor");
  return s;
}

}  // namespace trueaniso::py

BOOST_PYTHON_MODULE(_trueaniso) {
  using namespace trueaniso::py;
  np::initialize();
  bp::register_exception_translator<trueaniso::InputError>(&translateInputError);
  bp::scope().attr("__doc__") =
      "trueaniso engines: simplified Hertz-Mindlin DEM on a periodic cell (C++, Boost.Python).";
  exportScene();
  exportEngines();
  exportMeasures();
  exportStatics();
  exportFabric();
  exportControl();
  exportClump();
}
