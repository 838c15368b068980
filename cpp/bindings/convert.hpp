#pragma once
// Conversions of keyword values (py::handle) to C++ scalars for the parameter parsers. Every
// failure is a py::type_error (wrong kind of value) or py::value_error (right kind, bad value)
// whose message names the key; pybind's own cast errors (RuntimeError "Unable to cast") never
// reach the user.
#include <pybind11/pybind11.h>

#include <Eigen/Core>
#include <climits>
#include <cmath>
#include <cstdint>
#include <string>

namespace thinburn::bind {

namespace detail {
inline std::string type_name(const pybind11::handle& h) {
  return pybind11::str(pybind11::type::handle_of(h).attr("__name__")).cast<std::string>();
}

// Python bools and numpy bools (numpy.bool_ is neither int nor bool in Python's eyes).
inline bool is_bool_like(const pybind11::handle& h) {
  if (pybind11::isinstance<pybind11::bool_>(h)) return true;
  const std::string t = type_name(h);
  return t == "bool_" || t == "bool";
}

inline bool is_text(const pybind11::handle& h) {
  return pybind11::isinstance<pybind11::str>(h) || pybind11::isinstance<pybind11::bytes>(h);
}

// An object that is an integer in Python's sense (int, numpy integers: has __index__).
inline bool is_integral(const pybind11::handle& h) {
  return !is_bool_like(h) && !is_text(h) && PyIndex_Check(h.ptr());
}

// An integer object in Python's sense as a Python int; a TypeError naming key for any other.
inline pybind11::object as_index(const std::string& key, const pybind11::handle& h) {
  if (!is_integral(h)) throw pybind11::type_error(key + " must be an int, got " + type_name(h));
  pybind11::object i = pybind11::reinterpret_steal<pybind11::object>(PyNumber_Index(h.ptr()));
  if (!i) {
    PyErr_Clear();
    throw pybind11::type_error(key + " must be an int, got " + type_name(h));
  }
  return i;
}
}  // namespace detail

// The name of a keyword (keys of a parameter dict must be str).
inline std::string key_name(const pybind11::handle& k) {
  if (!pybind11::isinstance<pybind11::str>(k))
    throw pybind11::type_error("parameter names must be str, got " + detail::type_name(k));
  return k.cast<std::string>();
}

// A finite real number: int, float or a numpy scalar; bools and text are refused.
inline double to_double(const std::string& key, const pybind11::handle& h) {
  if (h.is_none() || detail::is_bool_like(h) || detail::is_text(h) || PySequence_Check(h.ptr()) ||
      !(PyFloat_Check(h.ptr()) || PyIndex_Check(h.ptr()) || PyNumber_Check(h.ptr())) ||
      PyComplex_Check(h.ptr()) || !pybind11::hasattr(h, "__float__"))
    throw pybind11::type_error(key + " must be a real number, got " + detail::type_name(h));
  const double x = PyFloat_AsDouble(h.ptr());
  if (x == -1.0 && PyErr_Occurred()) {
    PyErr_Clear();
    throw pybind11::value_error(key + " must be a finite real number (it does not fit a double)");
  }
  if (!std::isfinite(x)) throw pybind11::value_error(key + " must be finite, got " + std::to_string(x));
  return x;
}

// An integer in [lo, hi] (default: the range of a C int): int or a numpy integer; floats (even
// 2.0), bools and text are refused with a TypeError, out-of-range values with a ValueError.
inline int to_int(const std::string& key, const pybind11::handle& h, long long lo = INT_MIN,
                  long long hi = INT_MAX) {
  pybind11::object i = detail::as_index(key, h);
  int overflow = 0;
  const long long v = PyLong_AsLongLongAndOverflow(i.ptr(), &overflow);
  if (PyErr_Occurred()) PyErr_Clear();
  if (overflow != 0 || v < lo || v > hi) {
    const std::string got = pybind11::str(i).cast<std::string>();
    if (lo == INT_MIN && hi == INT_MAX)  // the field's own bounds are checked with the others
      throw pybind11::value_error(key + " must fit a C int (32 bits), got " + got);
    throw pybind11::value_error(key + " must be in [" + std::to_string(lo) + ", " + std::to_string(hi) +
                                "], got " + got);
  }
  return static_cast<int>(v);
}

// An integer in [0, 2^64 - 1] (a seed): int or a numpy integer, as to_int refuses others.
inline std::uint64_t to_uint64(const std::string& key, const pybind11::handle& h) {
  pybind11::object i = detail::as_index(key, h);
  const unsigned long long v = PyLong_AsUnsignedLongLong(i.ptr());
  if (PyErr_Occurred()) {
    PyErr_Clear();
    throw pybind11::value_error(key + " must be in [0, 2^64 - 1], got " + pybind11::str(i).cast<std::string>());
  }
  return v;
}

// A bool (Python or numpy); 0/1 integers are refused so a typo of a number is not read as a flag.
inline bool to_bool(const std::string& key, const pybind11::handle& h) {
  if (!detail::is_bool_like(h))
    throw pybind11::type_error(key + " must be a bool, got " + detail::type_name(h));
  return PyObject_IsTrue(h.ptr()) == 1;
}

// Three finite real numbers (a list, tuple or array of 3); a scalar or text is a TypeError.
inline Eigen::Vector3d to_vector3(const std::string& key, const pybind11::handle& h) {
  if (detail::is_text(h) || !PySequence_Check(h.ptr()))
    throw pybind11::type_error(key + " must be a sequence of 3 real numbers (x, y, z), got " +
                               detail::type_name(h));
  const Py_ssize_t n = PySequence_Size(h.ptr());
  if (n < 0) {
    PyErr_Clear();
    throw pybind11::type_error(key + " must be a sequence of 3 real numbers (x, y, z), got " +
                               detail::type_name(h));
  }
  if (n != 3)
    throw pybind11::value_error(key + " must have 3 components (x, y, z), got " + std::to_string(n));
  Eigen::Vector3d out;
  for (Py_ssize_t i = 0; i < 3; ++i) {
    pybind11::object e = pybind11::reinterpret_steal<pybind11::object>(PySequence_GetItem(h.ptr(), i));
    if (!e) {
      PyErr_Clear();
      throw pybind11::type_error(key + " must be a sequence of 3 real numbers (x, y, z)");
    }
    out[i] = to_double(key + "[" + std::to_string(i) + "]", e);
  }
  return out;
}

}  // namespace thinburn::bind
