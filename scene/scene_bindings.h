// How a scene rule's binding moves a checked TOML value into its member, and prints a member's
// value for the reference: read/show for each member type, at<T>(member pointers...) for a member
// reached through a chain of member pointers, custom<T>(set, show) for a setter that converts.
// Internal to precompute/ (scene_schema.cpp).
#pragma once
#include <toml++/toml.h>

#include <array>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

#include "scene_schema.h"

namespace snow::binding {

inline void read(const toml::node& n, double& v) { v = n.value<double>().value(); }
inline void read(const toml::node& n, std::optional<double>& v) { v = n.value<double>().value(); }
inline void read(const toml::node& n, int& v) { v = static_cast<int>(n.value<int64_t>().value()); }
inline void read(const toml::node& n, uint64_t& v) { v = static_cast<uint64_t>(n.value<int64_t>().value()); }
inline void read(const toml::node& n, bool& v) { v = n.value<bool>().value(); }
inline void read(const toml::node& n, std::string& v) { v = n.value<std::string>().value(); }
template <class E>
  requires std::is_enum_v<E>
inline void read(const toml::node& n, E& v) {
  v = enumFromName<E>(n.as_string()->get()).value();  // the rule's choices are the enum's names
}
inline void read(const toml::node& n, std::vector<std::string>& v) {
  v.clear();
  for (auto&& e : *n.as_array()) v.push_back(e.as_string()->get());
}
inline void read(const toml::node& n, std::vector<double>& v) {
  v.clear();
  for (auto&& e : *n.as_array()) v.push_back(e.value<double>().value());
}

inline std::string show(double v) { return numberText(v); }
inline std::string show(const std::optional<double>& v) { return v ? show(*v) : "none"; }
inline std::string show(int v) { return std::to_string(v); }
inline std::string show(uint64_t v) { return std::to_string(v); }
inline std::string show(bool v) { return v ? "true" : "false"; }
inline std::string show(const std::string& v) { return "\"" + v + "\""; }
template <class E>
  requires std::is_enum_v<E>
std::string show(E v) {
  return show(enumName(v));
}
template <class V>
std::string show(const std::vector<V>& v) {
  std::string s = "[";
  for (size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + show(v[i]);
  return s + "]";
}
template <class V, size_t N>
std::string show(const std::array<V, N>& v) {
  return show(std::vector<V>(v.begin(), v.end()));
}
template <class V, size_t N>
std::string show(const std::optional<std::array<V, N>>& v) {
  return v ? show(*v) : "none";
}

// at<T>(&A::b, &B::c, ...): the member obj.*b.*c... of an object of type T.
template <class T, class... M>
Bind<T> at(M... members) {
  return {[=](T& obj, const toml::node& n, const BindContext&) { read(n, (obj .* ... .* members)); },
          [=](const T& obj) { return show((obj .* ... .* members)); }};
}
template <class T>
Bind<T> custom(std::function<void(T&, const toml::node&, const BindContext&)> set, std::function<std::string(const T&)> show) {
  return {std::move(set), std::move(show)};
}

}  // namespace snow::binding
