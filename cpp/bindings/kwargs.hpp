#pragma once
// Parameter structs to and from Python by their tables (param_table.hpp): keyword dicts in,
// params dicts and the tables' descriptions out. Every bind_*.cpp that takes a struct's
// keywords uses these, so the names, conversions and errors are the same everywhere.
#include <pybind11/pybind11.h>

#include <string>
#include <vector>

#include "convert.hpp"
#include "param_table.hpp"

namespace thinburn::bind {

namespace detail {
// "'a', 'b', 'c'": the table's names, for the error of an unknown keyword.
template <class P>
std::string field_names(const std::vector<param::Field<P>>& fields) {
  std::string s;
  for (const auto& f : fields) s += (s.empty() ? "'" : ", '") + std::string(f.name) + "'";
  return s;
}
}  // namespace detail

// The value of one field from Python, converted as its kind asks (convert.hpp's errors name
// the field); the bounds are validate()'s.
template <class P>
void set_field(const param::Field<P>& f, P& p, const pybind11::handle& v) {
  switch (f.kind) {
    case param::Kind::Real: p.*f.real = to_double(f.name, v); break;
    case param::Kind::Int: p.*f.integer = to_int(f.name, v); break;
    case param::Kind::Seed: p.*f.seed = to_uint64(f.name, v); break;
    case param::Kind::Flag: p.*f.flag = to_bool(f.name, v); break;
    case param::Kind::Vector: p.*f.vector = to_vector3(f.name, v); break;
    case param::Kind::Choice: {
      // A name, or a value of the C++ enum's Python binding (of that type's name).
      if (!pybind11::isinstance<pybind11::str>(v)) {
        if (detail::type_name(v) != f.choice_type)
          throw pybind11::type_error(std::string(f.name) + " must be a str (" + param::choice_list(f) + ") or " +
                                     f.choice_type + ", got " + detail::type_name(v));
        f.set_choice(p, pybind11::int_(pybind11::reinterpret_borrow<pybind11::object>(v)).cast<int>());
        break;
      }
      const std::string s = v.cast<std::string>();
      for (std::size_t i = 0; i < f.choices.size(); ++i)
        if (s == f.choices[i]) {
          f.set_choice(p, static_cast<int>(i));
          return;
        }
      throw pybind11::value_error(std::string(f.name) + " must be " + param::choice_list(f) + ", got '" + s + "'");
    }
  }
}

// One field's value in Python: float, int, bool, a tuple (x, y, z) or a choice's name.
template <class P>
pybind11::object get_field(const param::Field<P>& f, const P& p) {
  switch (f.kind) {
    case param::Kind::Real: return pybind11::float_(p.*f.real);
    case param::Kind::Int: return pybind11::int_(p.*f.integer);
    case param::Kind::Seed: return pybind11::int_(p.*f.seed);
    case param::Kind::Flag: return pybind11::bool_(p.*f.flag);
    case param::Kind::Vector: {
      const Eigen::Vector3d& x = p.*f.vector;
      return pybind11::make_tuple(x.x(), x.y(), x.z());
    }
    case param::Kind::Choice: return pybind11::str(f.choices.at(f.get_choice(p)));
  }
  return pybind11::none();
}

// Apply keyword arguments to p by name, then validate(p) (the struct's own, found by ADL).
// An unknown name raises TypeError naming it and the known ones; what: "dynamics", ...
template <class P>
void apply_kwargs(P& p, const pybind11::handle& kw, const char* what) {
  const auto& fields = P::fields();
  for (const auto& item : pybind11::reinterpret_borrow<pybind11::dict>(kw)) {
    const std::string k = key_name(item.first);
    const param::Field<P>* f = param::find_field(fields, k);
    if (!f)
      throw pybind11::type_error("unexpected keyword argument '" + k + "'; " + what + " parameters are " +
                                 detail::field_names(fields));
    set_field(*f, p, item.second);
  }
  validate(p);
}

// Every field of p by name, in the table's order.
template <class P>
pybind11::dict params_dict(const P& p) {
  pybind11::dict d;
  for (const auto& f : P::fields()) d[f.name] = get_field(f, p);
  return d;
}

// The table for Python: per field (in order) a dict of name, kind ("real", "int", "seed",
// "flag", "vector", "choice"), default (P{}'s), low, high (None: no bound), low_open,
// high_open, choices (a choice's names, else empty) and doc.
template <class P>
pybind11::list describe_fields() {
  static const char* kinds[] = {"real", "int", "seed", "flag", "vector", "choice"};
  const P defaults{};
  pybind11::list out;
  for (const auto& f : P::fields()) {
    pybind11::list choices;
    for (const char* c : f.choices) choices.append(c);
    const auto end = [](bool has, double x) { return has ? pybind11::object(pybind11::float_(x)) : pybind11::none(); };
    out.append(pybind11::dict(pybind11::arg("name") = f.name, pybind11::arg("kind") = kinds[int(f.kind)],
                              pybind11::arg("default") = get_field(f, defaults),
                              pybind11::arg("low") = end(f.bounds.has_low(), f.bounds.low),
                              pybind11::arg("high") = end(f.bounds.has_high(), f.bounds.high),
                              pybind11::arg("low_open") = f.bounds.low_open,
                              pybind11::arg("high_open") = f.bounds.high_open,
                              pybind11::arg("choices") = choices, pybind11::arg("doc") = f.doc));
  }
  return out;
}

}  // namespace thinburn::bind
