#pragma once
// How the plugin's classes take their attributes from Python, the same for every class: a value
// of the wrong type, a read-only attribute, or a value out of range is a Python exception that
// names the attribute and what it takes, before the object changes.
//  - Types. YADE's own conversion fails with Boost's "No registered converter was able to produce
//    a C++ rvalue of type double from this Python object of type str" (at construction) or
//    "Python argument types in None.None(TrueTriaxialServo, str) did not match C++ signature"
//    (at assignment). The value is tried first on a default object of the class; refused, it is a
//    TypeError: "TrueTriaxialServo.b = '0.5': takes a number (float), not str".
//  - Read-only attributes (results) are refused at construction and by updateAttrs too, where
//    YADE would set them ("TrueTriaxialServo.reached is read-only: ...").
//  - Ranges. The class's postLoad refuses (std::invalid_argument, a ValueError); YADE's setter
//    has assigned before postLoad runs, so the hook puts the old value back. Every assignment runs
//    postLoad, those of a base class's attributes too (FabricRecorder's periods), and so does
//    updateAttrs, whose values all go back when one is refused.
// A class opts in with pyHandleCustomCtorArgs calling checkConstructorArguments, and the
// `__setattr__` and `updateAttrs` defs of PYTHON_ATTRIBUTES_DEFS in its YADE_CLASS_..._PY block.
#include <lib/serialization/Serializable.hpp>

#include <boost/python.hpp>

#include <functional>
#include <set>
#include <stdexcept>
#include <string>

#include "YadeRefusal.hpp"

namespace yade {
namespace trueanisoPlugin {

namespace bp = boost::python;

inline std::string pyRepr(const bp::object& v) {
  return bp::extract<std::string>(bp::object(bp::handle<>(PyObject_Repr(v.ptr()))))();
}

// What an attribute takes, from the value it holds (its C++ type, as YADE's converters give it).
inline std::string whatItTakes(const bp::object& current) {
  PyObject* p = current.ptr();
  if (PyBool_Check(p)) return "True or False";
  if (PyLong_Check(p)) return "an integer (int)";
  if (PyFloat_Check(p)) return "a number (float or int)";
  if (PyUnicode_Check(p)) return "a string (str)";
  const std::string type = Py_TYPE(p)->tp_name;
  if (type == "Vector6") return "6 numbers (a Vector6, tuple or list: Voigt xx, yy, zz, yz, xz, xy)";
  if (type == "Vector3") return "3 numbers (a Vector3, tuple or list)";
  if (type == "Matrix3") return "a 3x3 matrix (a Matrix3, or 3 rows of 3 numbers)";
  return "a " + type;
}

// The value's type as the refusal names it: "str", "tuple of 5".
inline std::string shownType(const bp::object& value) {
  std::string t = Py_TYPE(value.ptr())->tp_name;
  if (!PyUnicode_Check(value.ptr()) && PySequence_Check(value.ptr())) {
    const Py_ssize_t n = PySequence_Size(value.ptr());
    if (n >= 0) t += " of " + std::to_string(n);
    else PyErr_Clear();
  }
  return t;
}

inline void raise(PyObject* type, const std::string& message) {
  PyErr_SetString(type, message.c_str());
  bp::throw_error_already_set();
}

// A property of the class without a setter: a result of the engine (Attr::readonly).
inline bool readOnly(const bp::object& cls, const std::string& name) {
  PyObject* prop = PyObject_GetAttrString(cls.ptr(), name.c_str());
  if (!prop) {
    PyErr_Clear();
    return false;
  }
  bool ro = false;
  if (PyObject_TypeCheck(prop, &PyProperty_Type)) {
    PyObject* fset = PyObject_GetAttrString(prop, "fset");
    ro = fset == Py_None;
    Py_XDECREF(fset);
  }
  Py_DECREF(prop);
  return ro;
}

template <class T> struct PythonAttributes {
  static std::string className() { return T().getClassName(); }

  // The value's type against the attribute's: tried on a default object, whose pySetAttr converts
  // as YADE's constructor and setters do. `custom` attributes convert their values themselves.
  static void checkType(const std::string& name, const bp::object& value, const std::set<std::string>& custom) {
    if (custom.count(name)) return;
    T scratch;
    const bp::dict known = scratch.pyDict();
    if (!known.has_key(name)) return;  // YADE's own "No such attribute" (or a hidden one)
    try {
      scratch.pySetAttr(name, value);
    } catch (const bp::error_already_set&) {
      PyErr_Clear();
      raise(PyExc_TypeError, className() + "." + name + " = " + pyRepr(value) + ": takes " +
                                 whatItTakes(known[name]) + ", not " + shownType(value));
    }
  }

  static void refuseReadOnly(const std::string& name) {
    if (readOnly(bp::import("yade.wrapper").attr(className().c_str()), name))
      raise(PyExc_AttributeError, className() + "." + name + " is read-only: the engine sets it (help(" +
                                      className() + ") lists what can be given)");
  }

  // At construction: the types, and no read-only attribute.
  static void checkConstructorArguments(const bp::dict& kw, const std::set<std::string>& custom = {}) {
    const bp::list keys = kw.keys();
    for (long i = 0; i < bp::len(keys); ++i) {
      const std::string name = bp::extract<std::string>(keys[i]);
      refuseReadOnly(name);
      checkType(name, kw[keys[i]], custom);
    }
  }

  // obj.name = value: the type first, then the assignment and postLoad; refused, the old value back.
  static void setattr(bp::object self, const std::string& name, bp::object value) {
    refuseReadOnly(name);
    checkType(name, value, T::customAttributes());
    PyObject* old = PyObject_GetAttrString(self.ptr(), name.c_str());
    if (!old) PyErr_Clear();
    const bp::str key(name);
    auto putBack = [&] {
      if (old && PyObject_GenericSetAttr(self.ptr(), key.ptr(), old) != 0) PyErr_Clear();
    };
    if (PyObject_GenericSetAttr(self.ptr(), key.ptr(), value.ptr()) != 0) {
      PyObject *type, *val, *tb;
      PyErr_Fetch(&type, &val, &tb);
      putBack();
      Py_XDECREF(old);
      PyErr_Restore(type, val, tb);
      bp::throw_error_already_set();
    }
    T& t = bp::extract<T&>(self)();
    try {
      t.callPostLoad();  // a base class's attribute has no postLoad of its own
    } catch (...) {
      putBack();
      Py_XDECREF(old);
      throw;
    }
    Py_XDECREF(old);
  }

  // obj.updateAttrs(dict): the types first, then all together; refused, every old value back.
  static void updateAttrs(bp::object self, const bp::dict& d) {
    T& t = bp::extract<T&>(self)();
    const bp::list keys = d.keys();
    bp::dict old;
    for (long i = 0; i < bp::len(keys); ++i) {
      const std::string name = bp::extract<std::string>(keys[i]);
      refuseReadOnly(name);
      checkType(name, d[keys[i]], T::customAttributes());
      if (PyObject_HasAttrString(self.ptr(), name.c_str())) old[keys[i]] = self.attr(name.c_str());
    }
    try {
      t.pyUpdateAttrs(d);
    } catch (...) {
      const bp::list names = old.keys();
      for (long i = 0; i < bp::len(names); ++i) t.pySetAttr(bp::extract<std::string>(names[i]), old[names[i]]);
      throw;
    }
  }
};

// The defs that route a class's Python assignments through PythonAttributes.
#define PYTHON_ATTRIBUTES_DEFS(cls)                                                                         \
  .def("__setattr__", &trueanisoPlugin::PythonAttributes<cls>::setattr,                                      \
       "checked assignment: the type, then the range; a refused value leaves the old one")                   \
  .def("updateAttrs", &trueanisoPlugin::PythonAttributes<cls>::updateAttrs,                                  \
       "update attributes from a dict, checked together (b, sigmaZ and meanStress of a servo, say); refused, " \
       "every old value is kept")

// An attribute checked alone: a kernel of defaults given that one value, its own check run, its
// refusal raised as "Class.attribute = value: why".
template <class K>
void checkAlone(const char* cls, const char* name, const std::string& value, const std::function<void(K&)>& set,
                const std::function<void(K&)>& check) {
  K k;
  set(k);
  try {
    check(k);
  } catch (const std::exception& e) {
    refuse(cls, name, value, e.what());
  }
}

}  // namespace trueanisoPlugin
}  // namespace yade
