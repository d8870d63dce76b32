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

// Conversions from anything numpy.asarray accepts; shape errors raise ValueError naming `what`.
std::vector<Vec3> toVec3List(const bp::object& o, const std::string& what);
std::vector<Vec3i> toVec3iList(const bp::object& o, const std::string& what);
std::vector<Real> toRealList(const bp::object& o, const std::string& what);
std::vector<int> toIntList(const bp::object& o, const std::string& what);
Vec3 toVec3(const bp::object& o, const std::string& what);

}  // namespace trueaniso::py
