#pragma once
/// @brief One table per parameter struct (issue #11 item 5): every field once, with the name
/// the bindings take it by, where it lives in the struct, its bounds and a line of doc (its
/// unit first). validate(), the bindings' keyword parsing and parameter dicts, and the Python
/// key lists all read the table, so a field added to a struct and to its table is checked,
/// parsed, reported and listed everywhere at once.
#include <Eigen/Core>

#include <charconv>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace thinburn::param {

/// @brief Where a number may lie: from low to high, either end open; an infinite end is no bound.
struct Bounds {
  double low = -std::numeric_limits<double>::infinity();
  double high = std::numeric_limits<double>::infinity();
  bool low_open = false, high_open = false;

  bool has_low() const { return std::isfinite(low); }
  bool has_high() const { return std::isfinite(high); }
  bool contains(double x) const {
    return (low_open ? x > low : x >= low) && (high_open ? x < high : x <= high);
  }
};

inline Bounds unbounded() { return {}; }
inline Bounds at_least(double low) { return {low, Bounds{}.high, false, false}; }
inline Bounds above(double low) { return {low, Bounds{}.high, true, false}; }
/// @brief [low, high], or with open ends.
inline Bounds within(double low, double high, bool low_open = false, bool high_open = false) {
  return {low, high, low_open, high_open};
}

/// @brief The shortest text that reads back as x (0.9, 1e-08), whole numbers in full (1000000).
inline std::string number(double x) {
  if (x == std::floor(x) && std::fabs(x) < 1e15) return std::to_string(static_cast<long long>(x));
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, x);
  return std::string(buf, r.ptr);
}

/// @brief What a bound asks of a value, as an error names it: ">= 0", "> 0", "in (0, 1]";
/// a real also "finite and " before a one-sided bound, "finite" alone without one.
inline std::string requirement(const Bounds& b, bool real) {
  if (b.has_low() && b.has_high())
    return std::string("in ") + (b.low_open ? "(" : "[") + number(b.low) + ", " + number(b.high) +
           (b.high_open ? ")" : "]");
  const std::string finite = real ? "finite" : "";
  const std::string sep = real ? " and " : "";
  if (b.has_low()) return finite + sep + (b.low_open ? "> " : ">= ") + number(b.low);
  if (b.has_high()) return finite + sep + (b.high_open ? "< " : "<= ") + number(b.high);
  return finite;
}

/// @brief The kinds of value a field holds.
enum class Kind {
  Real,    ///< double, finite, within its bounds
  Int,     ///< int within its bounds
  Seed,    ///< std::uint64_t, any
  Flag,    ///< bool
  Vector,  ///< Eigen::Vector3d, finite
  Choice   ///< an enum, by the names of its values
};

/// @brief One field of a parameter struct P.
template <class P>
struct Field {
  const char* name = "";  ///< the keyword the bindings take and the key of a params dict
  Kind kind = Kind::Real;
  const char* doc = "";   ///< one line, its unit first
  Bounds bounds;          ///< Real and Int
  const char* hint = "";  ///< appended to a bound's error: what to do instead ("" none)
  double P::*real = nullptr;
  int P::*integer = nullptr;
  std::uint64_t P::*seed = nullptr;
  bool P::*flag = nullptr;
  Eigen::Vector3d P::*vector = nullptr;
  /// Choice: the names of the enum's values 0, 1, ..., its C++ name (the bindings also take
  /// its Python enum of that name) and the value's int in p.
  std::vector<const char*> choices;
  const char* choice_type = "";
  std::function<int(const P&)> get_choice;
  std::function<void(P&, int)> set_choice;
};

/// @brief A field of a number, a flag, a seed or a vector, its kind read from the member's type.
template <class P, class T>
Field<P> field(const char* name, T P::*m, Bounds b, const char* doc, const char* hint = "") {
  Field<P> f;
  f.name = name;
  f.doc = doc;
  f.bounds = b;
  f.hint = hint;
  if constexpr (std::is_same_v<T, double>) {
    f.kind = Kind::Real;
    f.real = m;
  } else if constexpr (std::is_same_v<T, int>) {
    f.kind = Kind::Int;
    f.integer = m;
  } else if constexpr (std::is_same_v<T, std::uint64_t>) {
    f.kind = Kind::Seed;
    f.seed = m;
  } else if constexpr (std::is_same_v<T, bool>) {
    f.kind = Kind::Flag;
    f.flag = m;
  } else {
    static_assert(std::is_same_v<T, Eigen::Vector3d>, "a field is a double, int, uint64, bool or Vector3d");
    f.kind = Kind::Vector;
    f.vector = m;
  }
  return f;
}

/// @brief The same without bounds (flags, seeds, vectors, unbounded numbers).
template <class P, class T>
Field<P> field(const char* name, T P::*m, const char* doc) {
  return field(name, m, unbounded(), doc);
}

/// @brief An enum field; names[i] is the name of the value E(i).
template <class P, class E>
Field<P> choice(const char* name, E P::*m, const char* type, std::vector<const char*> names, const char* doc) {
  Field<P> f;
  f.name = name;
  f.kind = Kind::Choice;
  f.doc = doc;
  f.choices = std::move(names);
  f.choice_type = type;
  f.get_choice = [m](const P& p) { return static_cast<int>(p.*m); };
  f.set_choice = [m](P& p, int v) { p.*m = static_cast<E>(v); };
  return f;
}

/// @brief The field of that name, null if none.
template <class P>
const Field<P>* find_field(const std::vector<Field<P>>& fields, const std::string& name) {
  for (const Field<P>& f : fields)
    if (name == f.name) return &f;
  return nullptr;
}

/// @brief "'a', 'b' or 'c'": a Choice field's names, as its errors list them.
template <class P>
std::string choice_list(const Field<P>& f) {
  std::string s;
  for (std::size_t i = 0; i < f.choices.size(); ++i)
    s += (i == 0 ? "'" : i + 1 == f.choices.size() ? " or '" : ", '") + std::string(f.choices[i]) + "'";
  return s;
}

/// @brief Throw std::invalid_argument naming f and its bound when p's value breaks it.
template <class P>
void check(const Field<P>& f, const P& p) {
  const auto fail = [&f](const std::string& need, const std::string& got) {
    throw std::invalid_argument(std::string(f.name) + " must be " + need + ", got " + got +
                                (*f.hint ? std::string("; ") + f.hint : std::string()));
  };
  switch (f.kind) {
    case Kind::Real: {
      const double x = p.*f.real;
      if (!std::isfinite(x) || !f.bounds.contains(x)) fail(requirement(f.bounds, true), number(x));
      break;
    }
    case Kind::Int: {
      const int x = p.*f.integer;
      if (!f.bounds.contains(x)) fail(requirement(f.bounds, false), std::to_string(x));
      break;
    }
    case Kind::Vector:
      if (!(p.*f.vector).allFinite()) throw std::invalid_argument(std::string(f.name) + " must be finite");
      break;
    case Kind::Choice: {
      const int c = f.get_choice(p);
      if (c < 0 || c >= static_cast<int>(f.choices.size())) fail(choice_list(f), std::to_string(c));
      break;
    }
    case Kind::Seed:
    case Kind::Flag:
      break;
  }
}

/// @brief Check every field of p in the table's order: the first invalid one throws.
template <class P>
void check_all(const std::vector<Field<P>>& fields, const P& p) {
  for (const Field<P>& f : fields) check(f, p);
}

}  // namespace thinburn::param
