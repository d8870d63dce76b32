#pragma once
// Bulk data crosses the Python boundary as numpy arrays (copies). No Eigen converters are
// registered: inside yade-double YADE owns those for Vector3r/Matrix3r.
#include <boost/python.hpp>
#include <boost/python/numpy.hpp>
#include <string>
#include <vector>

#include "core/Types.hpp"

namespace trueaniso::py {

namespace bp = boost::python;
namespace np = boost::python::numpy;

np::ndarray toNumpy(const std::vector<Vec3>& v);
np::ndarray toNumpy(const std::vector<Vec3i>& v);
np::ndarray toNumpy(const std::vector<Real>& v);
np::ndarray toNumpy(const std::vector<int>& v);
np::ndarray toNumpy(const Vec3& v);
np::ndarray toNumpy(const Mat3& m);
np::ndarray toNumpy(const Vec6& v);

// Conversions from anything numpy.asarray accepts; shape errors raise ValueError naming `what`.
std::vector<Vec3> toVec3List(const bp::object& o, const std::string& what);
std::vector<Vec3i> toVec3iList(const bp::object& o, const std::string& what);
std::vector<Real> toRealList(const bp::object& o, const std::string& what);
std::vector<int> toIntList(const bp::object& o, const std::string& what);
Vec3 toVec3(const bp::object& o, const std::string& what);
Vec6 toVec6(const bp::object& o, const std::string& what);
Mat3 toMatrix3(const bp::object& o, const std::string& what);  // anything of 9 numbers, row major
// A stress given as 3 normal components (the shear ones zero), 6 Voigt components
// (xx, yy, zz, yz, xz, xy) or a 3x3 tensor (its symmetric part).
Vec6 toStressVoigt(const bp::object& o, const std::string& what);

}  // namespace trueaniso::py
